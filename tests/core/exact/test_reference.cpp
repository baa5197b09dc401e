#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"

#include <catch2/catch.hpp>

#include <algorithm>

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

TEST_CASE("the sweep of boxes gives box_intersection_d's pairs, and the filtered narrow phase the exact test's",
          "[reference]") {
  // Meshes whose boxes touch, coincide and nest: two spheres, a sphere and its copy, a grid
  // through a sphere, a box on a box (touching faces), far from the origin too.
  std::vector<std::pair<Mesh, Mesh>> cases;
  cases.emplace_back(make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24), make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 10, 20));
  cases.emplace_back(make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24), make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24));
  cases.emplace_back(make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24),
                     make_grid(Vec3(-1.5, -1.5, 0.1), Vec3(3, 0, 0.2), Vec3(0, 3, 0), 7, 5));
  cases.emplace_back(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), make_box(Vec3(0, 0, 1), Vec3(1, 1, 2)));
  cases.emplace_back(make_uv_sphere(Vec3(1e6, -1e6, 1e6), 1e-3, 12, 24),
                     make_uv_sphere(Vec3(1e6 + 1.2e-3, -1e6, 1e6), 0.8e-3, 10, 20));
  for (const auto& [a, b] : cases) {
    std::vector<std::uint32_t> ta(a.triangles.size()), tb(b.triangles.size());
    for (std::uint32_t i = 0; i < ta.size(); ++i) ta[i] = i;
    for (std::uint32_t i = 0; i < tb.size(); ++i) tb[i] = i;
    std::vector<std::uint64_t> swept, cgal;
    BoxScratch scratch;
    box_overlap_pairs(a, ta, b, tb, swept, &scratch);
    cgal_box_overlap_pairs(a, ta, b, tb, cgal);
    std::sort(swept.begin(), swept.end());
    std::sort(cgal.begin(), cgal.end());
    CHECK(std::adjacent_find(swept.begin(), swept.end()) == swept.end());  // each pair once
    cgal.erase(std::unique(cgal.begin(), cgal.end()), cgal.end());
    CHECK_FALSE(cgal.empty());
    CHECK(swept == cgal);
    // The narrow phase (with its double-certified separation test) against the exact test.
    std::vector<Contact> contacts;
    narrow_phase(a, b, swept, contacts);
    std::vector<std::uint64_t> found;
    for (const Contact& c : contacts) found.push_back(pack_pair(c.tri_a, c.tri_b));
    CHECK(found == exact_colliding_pairs(a, b));
  }
}
