// The worker pool runs every lane once per job, rethrows a lane's exception, and the narrow
// phase split over it gives the serial narrow phase's answer, in the same order.
#include "core/id_map.h"
#include "core/narrow_phase.h"
#include "core/primitives.h"
#include "core/reference.h"
#include "core/worker_pool.h"

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

TEST_CASE("the narrow phase split over a pool equals the serial narrow phase", "[pool]") {
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 24, 48);
  const Mesh b = make_grid(Vec3(-1.5, -1.5, -0.2), Vec3(3, 0, 0.6), Vec3(0, 3, 0), 20, 20);
  std::vector<std::uint64_t> candidates;  // every pair: most are disjoint, some collide
  for (std::uint32_t i = 0; i < a.triangles.size(); i += 3)
    for (std::uint32_t j = 0; j < b.triangles.size(); ++j) candidates.push_back(pack_pair(i, j));
  std::vector<Contact> serial, parallel;
  narrow_phase(a, b, candidates, serial);
  WorkerPool pool(3);
  std::vector<std::uint8_t> hits;
  narrow_phase(a, b, candidates, parallel, pool, hits);
  REQUIRE(serial.size() > 10);
  REQUIRE(parallel.size() == serial.size());
  for (std::size_t i = 0; i < serial.size(); ++i) {
    CHECK(parallel[i].tri_a == serial[i].tri_a);
    CHECK(parallel[i].tri_b == serial[i].tri_b);
    CHECK(parallel[i].p == serial[i].p);
    CHECK(parallel[i].q == serial[i].q);
    CHECK(parallel[i].kind == serial[i].kind);
  }
}
