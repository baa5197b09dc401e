#include "peelcd/core/id_map.h"
#include "peelcd/core/narrow_phase.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/reference.h"

#include <catch2/catch.hpp>

using namespace peelcd;

TEST_CASE("the box_intersection_d reference equals brute force over all triangle pairs", "[reference]") {
  // Two interpenetrating spheres, and a grid slicing one of them.
  const Mesh s1 = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const Mesh s2 = make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 10, 20);
  const Mesh grid = make_grid(Vec3(-1.5, -1.5, 0.1), Vec3(3, 0, 0.2), Vec3(0, 3, 0), 7, 5);
  for (const auto& [a, b] : {std::pair<const Mesh&, const Mesh&>{s1, s2}, {s1, grid}, {grid, s2}}) {
    std::vector<std::uint64_t> brute;
    for (std::uint32_t i = 0; i < a.triangles.size(); ++i)
      for (std::uint32_t j = 0; j < b.triangles.size(); ++j)
        if (triangles_intersect(corners(a, i), corners(b, j))) brute.push_back(pack_pair(i, j));
    const auto fast = exact_colliding_pairs(a, b);
    CHECK_FALSE(brute.empty());
    CHECK(fast == brute);  // same pairs, A's index first
  }
}

TEST_CASE("separated meshes have no colliding pairs", "[reference]") {
  CHECK(exact_colliding_pairs(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), make_box(Vec3(1.001, 0, 0), Vec3(2, 1, 1))).empty());
}
