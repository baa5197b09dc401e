// The worker pool (core/worker_pool.h) runs every lane once per job and rethrows a lane's
// exception; the host resolve's lanes run on it. Its for_each() (the World's and the frame
// API's loops) gives each lane a range of the items first.
#include "peelcd/core/worker_pool.h"

#include <catch2/catch.hpp>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace peelcd;

TEST_CASE("a worker pool runs each lane once per job and rethrows a lane's exception", "[pool]") {
  for (unsigned lanes : {1u, 2u, 5u}) {
    WorkerPool pool(lanes);
    REQUIRE(pool.lanes() == lanes);
    for (int job = 0; job < 50; ++job) {
      std::vector<int> runs(lanes, 0);
      auto fn = [&](unsigned lane) { ++runs[lane]; };
      pool.run(fn);
      CHECK(runs == std::vector<int>(lanes, 1));
    }
    auto failing = [&](unsigned lane) {
      if (lane == lanes - 1) throw std::runtime_error("lane failed");
    };
    CHECK_THROWS_WITH(pool.run(failing), "lane failed");
    std::atomic<int> after{0};
    auto fine = [&](unsigned) { ++after; };
    pool.run(fine);  // still usable
    CHECK(after == int(lanes));
  }
}

TEST_CASE("a worker pool's for_each calls every item once, each lane first on its own range", "[pool]") {
  for (unsigned lanes : {1u, 2u, 5u}) {
    WorkerPool pool(lanes);
    for (std::size_t n : {0, 1, 2, 3, 7, 64, 1000}) {
      for (int job = 0; job < 5; ++job) {
        std::vector<std::atomic<int>> calls(n);
        std::vector<std::vector<std::size_t>> order(lanes);  // each lane's items, in its order
        std::atomic<int> bad_lane{0};
        pool.for_each(n, [&](std::size_t i, unsigned lane) {  // (no Catch2 assertion off the main thread)
          if (lane >= lanes) {
            ++bad_lane;
            return;
          }
          ++calls[i];
          order[lane].push_back(i);
        });
        REQUIRE(bad_lane == 0);
        for (std::size_t i = 0; i < n; ++i) CHECK(calls[i] == 1);
        // A lane's items from its own range [n l / lanes, n (l + 1) / lanes) are a prefix of
        // it, in order; those from another lane's range come from its back, in reverse order.
        for (unsigned l = 0; l < lanes; ++l) {
          const std::size_t begin = n * l / lanes, end = n * (l + 1) / lanes;
          std::size_t own = 0;
          std::vector<std::size_t> last_stolen(lanes, n);
          for (const std::size_t i : order[l]) {
            if (i >= begin && i < end) {
              CHECK(i == begin + own);
              ++own;
            } else {
              unsigned victim = 0;
              while (!(i >= n * victim / lanes && i < n * (victim + 1) / lanes)) ++victim;
              CHECK(i < last_stolen[victim]);
              last_stolen[victim] = i;
            }
          }
        }
      }
    }
    // With as many items as lanes and every item waiting for all lanes to start one, no lane
    // can take another's: item l runs on lane l (the same item, the same lane, call after call).
    for (int job = 0; job < 20; ++job) {
      std::atomic<unsigned> started{0};
      std::vector<unsigned> lane_of(lanes, lanes);
      pool.for_each(lanes, [&](std::size_t i, unsigned lane) {
        lane_of[i] = lane;
        ++started;
        while (started.load() < lanes) std::this_thread::yield();
      });
      for (unsigned l = 0; l < lanes; ++l) CHECK(lane_of[l] == l);
    }
    CHECK_THROWS_WITH(pool.for_each(100, [](std::size_t i, unsigned) {
                        if (i == 57) throw std::runtime_error("item failed");
                      }),
                      "item failed");
  }
}
