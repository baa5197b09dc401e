// The World's timing of its two routes (core/world/route_timer.h): the schedule of comparisons,
// the untimed first frame of each stint, the choice, the interval's growth and reset, and a
// change of the scene's pair count.
#include "world/route_timer.h"

#include <catch2/catch.hpp>

#include <functional>
#include <vector>

using peelcd::RouteTimer;

namespace {

// Runs `frames` frames, each timed by `ms(route, stint frame)`; returns the routes taken.
std::vector<RouteTimer::Route> run(RouteTimer& t, int frames, const std::function<double(RouteTimer::Route)>& ms,
                                   std::size_t pairs = 10) {
  std::vector<RouteTimer::Route> taken;
  for (int f = 0; f < frames; ++f) {
    taken.push_back(t.next());
    t.record(ms(t.next()), pairs);
  }
  return taken;
}

int count(const std::vector<RouteTimer::Route>& v, RouteTimer::Route r) {
  int n = 0;
  for (const RouteTimer::Route x : v) n += x == r;
  return n;
}

}  // namespace

TEST_CASE("route timer: both routes timed first, the faster kept", "[world][route]") {
  for (const bool image_faster : {true, false}) {
    INFO("image faster " << image_faster);
    RouteTimer t;
    CHECK(t.comparing());
    const auto ms = [&](RouteTimer::Route r) { return (r == RouteTimer::image) == image_faster ? 5.0 : 10.0; };
    // An untimed frame and two timed ones on the routed path, then the same on the image route.
    const std::vector<RouteTimer::Route> first = run(t, 6, ms);
    CHECK(first == std::vector<RouteTimer::Route>{RouteTimer::routed, RouteTimer::routed, RouteTimer::routed,
                                                   RouteTimer::image, RouteTimer::image, RouteTimer::image});
    CHECK_FALSE(t.comparing());
    const RouteTimer::Route best = image_faster ? RouteTimer::image : RouteTimer::routed;
    CHECK(t.choice() == best);
    CHECK(t.next() == best);
    CHECK(t.interval() == RouteTimer::kFirstInterval);
    // The choice holds for the interval, then the other route is timed again (an untimed frame
    // and two timed), then the choice resumes with the interval doubled.
    const std::vector<RouteTimer::Route> later = run(t, int(RouteTimer::kFirstInterval) + 3, ms);
    CHECK(count(later, best) == int(RouteTimer::kFirstInterval));
    CHECK(t.choice() == best);
    CHECK(t.next() == best);
    CHECK(t.interval() == 2 * RouteTimer::kFirstInterval);
  }
}

TEST_CASE("route timer: the first frame of each stint is not timed", "[world][route]") {
  // Each route's first frame after a switch costs 100x (uploads, refits caught up): the choice
  // is still the faster route's steady frames.
  RouteTimer t;
  RouteTimer::Route last = RouteTimer::routed;
  bool first_of_stint = true;
  for (int f = 0; f < 6; ++f) {
    const RouteTimer::Route r = t.next();
    first_of_stint = f == 0 || r != last;
    last = r;
    const double steady = r == RouteTimer::image ? 4.0 : 6.0;
    t.record(first_of_stint ? 100.0 * steady : steady, 10);
  }
  CHECK(t.choice() == RouteTimer::image);
  CHECK(t.mean(RouteTimer::image) == 4.0);
  CHECK(t.mean(RouteTimer::routed) == 6.0);
}

TEST_CASE("route timer: a changed choice starts the interval over, and the interval is bounded", "[world][route]") {
  RouteTimer t;
  double image_ms = 5.0;
  const auto ms = [&](RouteTimer::Route r) { return r == RouteTimer::image ? image_ms : 10.0; };
  run(t, 6, ms);
  REQUIRE(t.choice() == RouteTimer::image);
  // Held through many comparisons: the interval doubles to its bound.
  for (int i = 0; i < 12; ++i) run(t, int(t.interval()) + 3, ms);
  CHECK(t.choice() == RouteTimer::image);
  CHECK(t.interval() == RouteTimer::kMaxInterval);
  // The image route becomes the slower: the next comparison finds it and starts over.
  image_ms = 20.0;
  const std::vector<RouteTimer::Route> taken = run(t, int(RouteTimer::kMaxInterval) + 3, ms);
  CHECK(count(taken, RouteTimer::routed) == 3);  // the routed path timed again
  CHECK(t.choice() == RouteTimer::routed);
  CHECK(t.next() == RouteTimer::routed);
  CHECK(t.interval() == RouteTimer::kFirstInterval);
}

TEST_CASE("route timer: a pair count outside half to double the chosen one's times both routes again", "[world][route]") {
  RouteTimer t;
  double image_ms = 5.0;
  const auto ms = [&](RouteTimer::Route r) { return r == RouteTimer::image ? image_ms : 10.0; };
  run(t, 6, ms, 100);
  REQUIRE(t.choice() == RouteTimer::image);
  run(t, 3, ms, 60);  // within [50, 200]: the choice holds
  CHECK_FALSE(t.comparing());
  image_ms = 30.0;  // the scene grew, and the image route with it
  t.record(ms(t.next()), 250);
  CHECK(t.comparing());
  // The current route timed afresh (its frames from before the change dropped), then the other.
  const std::vector<RouteTimer::Route> taken = run(t, 5, ms, 250);
  CHECK(taken == std::vector<RouteTimer::Route>{RouteTimer::image, RouteTimer::image, RouteTimer::routed,
                                                RouteTimer::routed, RouteTimer::routed});
  CHECK_FALSE(t.comparing());
  CHECK(t.choice() == RouteTimer::routed);
}
