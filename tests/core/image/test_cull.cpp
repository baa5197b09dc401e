// Contact-region culling (core/image/cull.h) must never drop a triangle of a colliding pair, whatever
// the scale, offset or degeneracy; it must drop what is far from the other object.
#include "adversarial.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>

using namespace peelcd;
using namespace peelcd::test;

namespace {

bool kept(const std::vector<std::uint32_t>& list, std::uint32_t tri) {
  return std::binary_search(list.begin(), list.end(), tri);
}

// Every exact colliding pair survives, and the shrunk box holds where they meet.
void check_conservative(const Mesh& a, const Mesh& b) {
  ContactCull cull;
  cull_to_contact_region(a, b, intersection(bounds(a), bounds(b)), cull);
  REQUIRE(std::is_sorted(cull.kept_a.begin(), cull.kept_a.end()));
  REQUIRE(std::is_sorted(cull.kept_b.begin(), cull.kept_b.end()));
  for (std::uint64_t e : exact_colliding_pairs(a, b)) {
    INFO("pair " << pair_a(e) << ", " << pair_b(e));
    CHECK(kept(cull.kept_a, pair_a(e)));
    CHECK(kept(cull.kept_b, pair_b(e)));
    CHECK(intersection(triangle_bounds(a, pair_a(e)), triangle_bounds(b, pair_b(e))).overlaps(cull.box));
  }
}

Mesh soup(std::mt19937_64& rng, const Vec3& lo, double size, int count, double tri_size) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Mesh m;
  for (int t = 0; t < count; ++t) {
    const Vec3 c = lo + size * Vec3(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) m.vertices.push_back(c + tri_size * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5));
    const auto v = std::uint32_t(3 * t);
    m.triangles.push_back({v, v + 1, v + 2});
  }
  return m;
}

void append(Mesh& m, const TriangleCorners& t) {
  const auto v = std::uint32_t(m.vertices.size());
  for (const Vec3& p : t) m.vertices.push_back(p);
  m.triangles.push_back({v, v + 1, v + 2});
}

}  // namespace

TEST_CASE("contact-region culling keeps every colliding pair of random triangle soups", "[cull]") {
  std::mt19937_64 rng(20261123);
  for (int round = 0; round < 40; ++round) {
    const double scale = round % 4 == 0 ? 1e-6 : round % 4 == 1 ? 1e6 : 1.0;
    const Vec3 offset = Vec3::Constant(round % 3 == 0 ? 1e6 * scale : 0.0);
    Mesh a = soup(rng, offset, scale, 300, 0.15 * scale);
    Mesh b = soup(rng, offset + Vec3::Constant(0.3 * scale), scale, 300, 0.15 * scale);
    INFO("round " << round);
    check_conservative(a, b);
  }
}

TEST_CASE("contact-region culling keeps adversarial pairs hidden among distractors", "[cull]") {
  // Touching, coplanar, near-coplanar, sliver and shared-vertex pairs, each with random
  // triangles around it that make a grid of many cells.
  AdversarialGenerator gen(7);
  std::mt19937_64 rng(11);
  for (int i = 0; i < 400; ++i) {
    const AdversarialCase c = gen.next();
    const double size = 16.0 * c.scale;
    const Vec3 lo = Vec3::Constant(c.offset - 8.0 * c.scale);
    Mesh a = soup(rng, lo, size, 40, 0.5 * c.scale);
    Mesh b = soup(rng, lo, size, 40, 0.5 * c.scale);
    append(a, c.a);
    append(b, c.b);
    INFO("case " << i << " (" << kFamilyNames[int(c.family)] << ")");
    check_conservative(a, b);
  }
}

TEST_CASE("contact-region culling drops what is far from the other object", "[cull]") {
  SECTION("a plane through a sphere: only the band around the circle of contact stays") {
    const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 24, 48);
    const Mesh plane = make_grid(Vec3(-1.5, -1.5, -0.2), Vec3(3, 0, 0.6), Vec3(0, 3, 0), 12, 12);
    ContactCull cull;
    const Aabb roi = intersection(bounds(sphere), bounds(plane));
    cull_to_contact_region(sphere, plane, roi, cull);
    CHECK(cull.stats.rounds >= 1);
    CHECK(cull.stats.kept_a < cull.stats.in_roi_a / 2);
    CHECK(cull.stats.kept_b < cull.stats.in_roi_b);
    CHECK(cull.kept_a.size() == cull.stats.kept_a);
    CHECK(roi.extent().prod() > cull.box.extent().prod());
    check_conservative(sphere, plane);
  }
  SECTION("boxes overlap, surfaces do not: nothing is kept, the box is empty") {
    // Two thin diagonal slabs whose boxes overlap in a corner region they do not reach.
    Mesh a, b;
    append(a, {Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(0, 0, 0.1)});
    append(a, {Vec3(1, 1, 0), Vec3(1, 1, 0.1), Vec3(0, 0, 0.1)});
    append(b, {Vec3(0.9, 0, 0), Vec3(1.9, 1, 0), Vec3(0.9, 0, 0.1)});
    append(b, {Vec3(1.9, 1, 0), Vec3(1.9, 1, 0.1), Vec3(0.9, 0, 0.1)});
    REQUIRE(bounds(a).overlaps(bounds(b)));
    REQUIRE(exact_colliding_pairs(a, b).empty());
    // Many small triangles along each slab give the grid its resolution.
    ContactCull cull;
    Mesh fine_a, fine_b;
    for (int i = 0; i < 50; ++i) {
      const double s = i / 50.0, e = (i + 1) / 50.0;
      append(fine_a, {Vec3(s, s, 0), Vec3(e, e, 0), Vec3(s, s, 0.1)});
      append(fine_b, {Vec3(0.9 + s, s, 0), Vec3(0.9 + e, e, 0), Vec3(0.9 + s, s, 0.1)});
    }
    REQUIRE(exact_colliding_pairs(fine_a, fine_b).empty());
    cull_to_contact_region(fine_a, fine_b, intersection(bounds(fine_a), bounds(fine_b)), cull);
    CHECK(cull.kept_a.empty());
    CHECK(cull.kept_b.empty());
    CHECK(cull.box.empty());
  }
  SECTION("boxes touching face to face: a flat ROI keeps the touching faces") {
    const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
    const Mesh b = make_box(Vec3(1, 0.2, 0.2), Vec3(2, 0.8, 0.8));
    ContactCull cull;
    cull_to_contact_region(a, b, intersection(bounds(a), bounds(b)), cull);
    CHECK_FALSE(cull.box.empty());
    CHECK(cull.box.extent().x() == 0.0);
    CHECK_FALSE(cull.kept_a.empty());
    CHECK_FALSE(cull.kept_b.empty());
    check_conservative(a, b);
  }
}

TEST_CASE("contact-region culling reports the kept triangles' median edge", "[cull]") {
  // Two grids of right isosceles triangles crossing: legs 0.1 (A) and 0.4 (B). A keeps more
  // triangles near the line of contact, so the median is A's mean edge, (2 + sqrt 2) / 3 * 0.1.
  const Mesh a = make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 20, 20);
  const Mesh b = make_grid(Vec3(-1, 0.05, -1), Vec3(2, 0, 0), Vec3(0, 0, 2), 5, 5);
  ContactCull cull;
  cull_to_contact_region(a, b, intersection(bounds(a), bounds(b)), cull);
  REQUIRE(cull.kept_a.size() > cull.kept_b.size());
  CHECK_THAT(cull.median_edge, Catch::Matchers::WithinRel((2.0 + std::sqrt(2.0)) / 3.0 * 0.1, 1e-12));
  cull_to_contact_region(a, make_box(Vec3(5, 5, 5), Vec3(6, 6, 6)), intersection(bounds(a), bounds(b)), cull);
  CHECK(cull.median_edge == 0.0);  // nothing kept
}
