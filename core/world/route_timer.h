#pragma once
// The World's choice between its two routes for a frame's pairs under Stage::automatic on a GPU
// (World::time_routes()): the router's per-pair models over the traversed pairs ("routed": on
// every scene measured, the exact path) or every pair to the resident image route, as
// Stage::image runs it (untraversed, deforming bodies' refits put off). Both give the same
// contacts; which is faster depends on the scene and the device (docs/backends.md, "The World
// times its routes"), and the per-pair models cannot see it before the traversal the image route
// skips. So the World times its own frames: each route `kTimedFrames` frames after an untimed
// one (uploads, refits put off or caught up), the faster kept for `interval` frames, then the
// other timed again; the interval doubles while the choice holds (up to `kMaxInterval`) and
// starts over when it changes. A frame whose pair count left [half, double] of the count at the
// choice times both routes again.
//
// Pure bookkeeping (no clock): the World calls next() before a frame and record() after it.
#include <algorithm>
#include <cstddef>

namespace peelcd {

class RouteTimer {
 public:
  enum Route : int { routed = 0, image = 1 };
  static constexpr int kTimedFrames = 2;
  static constexpr std::size_t kFirstInterval = 32;
  static constexpr std::size_t kMaxInterval = 1024;

  // The route of the next frame.
  Route next() const { return route_; }
  // The next frame belongs to a comparison (a route being timed), not to a choice.
  bool comparing() const { return comparing_; }
  // The choice of the last comparison (routed before the first).
  Route choice() const { return choice_; }
  std::size_t interval() const { return interval_; }

  // The frame just run on next()'s route took `ms` and had `pairs` pairs.
  void record(double ms, std::size_t pairs) {
    if (!untimed_) add(route_, ms);
    untimed_ = false;
    if (!comparing_) {
      if (pairs * 2 < pairs_at_choice_ || pairs > 2 * pairs_at_choice_) {  // the scene changed: both again
        comparing_ = true;
        count_[0] = count_[1] = 0;
        return;
      }
      if (--countdown_ > 0) return;
      comparing_ = true;  // the other route, timed again
      switch_to(other(route_));
      count_[route_] = 0;
      return;
    }
    if (count_[route_] < kTimedFrames) return;
    if (count_[other(route_)] < kTimedFrames) {
      switch_to(other(route_));
      count_[route_] = 0;
      return;
    }
    const Route best = mean(image) < mean(routed) ? image : routed;
    interval_ = decided_ && best == choice_ ? std::min(2 * interval_, kMaxInterval) : kFirstInterval;
    choice_ = best;
    decided_ = true;
    comparing_ = false;
    countdown_ = interval_;
    pairs_at_choice_ = pairs;
    if (best != route_) switch_to(best);
  }

  // The last timed frames' mean of a route (0 before any).
  double mean(Route r) const {
    double sum = 0.0;
    for (int i = 0; i < count_[r]; ++i) sum += ms_[r][(slot_[r] + kTimedFrames - 1 - i) % kTimedFrames];
    return count_[r] ? sum / count_[r] : 0.0;
  }

 private:
  static Route other(Route r) { return r == image ? routed : image; }
  void switch_to(Route r) {
    route_ = r;
    untimed_ = true;  // its first frame (uploads, refits put off or caught up) not timed
  }
  void add(Route r, double ms) {  // the last kTimedFrames frames kept
    ms_[r][slot_[r]] = ms;
    slot_[r] = (slot_[r] + 1) % kTimedFrames;
    count_[r] = std::min(count_[r] + 1, kTimedFrames);
  }

  Route route_ = routed, choice_ = routed;
  bool comparing_ = true, decided_ = false;
  bool untimed_ = true;  // the next frame is the first on route_ since it was switched to
  int count_[2] = {0, 0};  // timed frames of each route kept (at most kTimedFrames)
  int slot_[2] = {0, 0};   // where each route's next timed frame goes
  double ms_[2][kTimedFrames] = {};
  std::size_t interval_ = kFirstInterval, countdown_ = 0, pairs_at_choice_ = 0;
};

}  // namespace peelcd
