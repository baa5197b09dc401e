// The worker pool (core/worker_pool.h) runs every lane once per job and rethrows a lane's
// exception; the host resolve's lanes run on it.
#include "peelcd/core/worker_pool.h"

#include <catch2/catch.hpp>

#include <atomic>
#include <stdexcept>

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
