// Penetration depth (peelcd/core/exact/depth.h) on the depth classes (eval/classes.cpp): moving A by
// (d + 1e-6 of the scene's size) n leaves no intersecting triangle pair and no containment
// (exact), moving it by 0.97 d still overlaps, and the swapped pair gives (-n, d). Proximity
// (peelcd/core/exact/proximity.h) on the same classes against CGAL's exact distances.
#include "peelcd/core/exact/depth.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/mesh_io.h"
#include "stride.h"  // PEELCD_TEST_STRIDE: the sanitizer stage runs every Nth case of the long sweeps

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

using namespace peelcd;

namespace {

Mesh translated(Mesh m, const Vec3& t) {
  for (Vec3& v : m.vertices) v += t;
  return m;
}

std::vector<Contact> contacts_of(const Mesh& a, const Mesh& b) {
  std::vector<Contact> out;
  for (const std::uint64_t k : exact_colliding_pairs(a, b)) {
    Contact c;
    c.tri_a = pair_a(k);
    c.tri_b = pair_b(k);
    test_triangle_pair(corners(a, c.tri_a), corners(b, c.tri_b), c);
    out.push_back(c);
  }
  return out;
}

// A and B share interior: a crossing contact, or one inside the other (exact tests).
bool overlapping(const Mesh& a, const Mesh& b) {
  const std::vector<Contact> c = contacts_of(a, b);
  std::string note;
  const Relation r = relate(a, b, c, note);
  return r == Relation::crossing || r == Relation::a_inside_b || r == Relation::b_inside_a;
}

// Any contact at all (touching counts), or containment.
bool meeting(const Mesh& a, const Mesh& b) {
  if (!exact_colliding_pairs(a, b).empty()) return true;
  std::string note;
  const Relation r = relate(a, b, {}, note);
  return r != Relation::disjoint;
}

}  // namespace

TEST_CASE("depth: moving A by d + 1e-6 of the scene along n separates, by 0.97 d does not, swapped gives (-n, d)", "[depth]") {
  for (const DepthClass& c : depth_classes()) {
    INFO(c.scene.name);
    const Mesh& a = c.scene.objects[0].mesh;
    const Mesh& b = c.scene.objects[1].mesh;
    const PenetrationDepth pd = penetration_depth(a, b, contacts_of(a, b));
    REQUIRE(pd.known);
    CHECK(std::abs(pd.direction.norm() - 1.0) < 1e-12);
    Aabb scene = bounds(a);
    scene.extend(bounds(b).lo);
    scene.extend(bounds(b).hi);
    const double size = scene.extent().maxCoeff();
    INFO("depth " << pd.depth << " along " << pd.direction.transpose() << " from " << pd.source);
    if (c.expected >= 0.0) CHECK(pd.depth == Approx(c.expected).margin(1e-9 * size));
    CHECK_FALSE(meeting(translated(a, (pd.depth + 1e-6 * size) * pd.direction), b));
    if (pd.depth > 0.0) CHECK(overlapping(translated(a, 0.97 * pd.depth * pd.direction), b));
    // Swapped: B moved by d along -n.
    std::vector<Contact> swapped = contacts_of(b, a);
    const PenetrationDepth ps = penetration_depth(b, a, swapped);
    REQUIRE(ps.known);
    CHECK(ps.depth == Approx(pd.depth).epsilon(0.01).margin(1e-9 * size));
    CHECK((ps.direction + pd.direction).norm() < 1e-9);
  }
}

TEST_CASE("depth: along one direction, the least separating translation", "[depth]") {
  const Mesh a = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = box_mesh(Vec3(0.7, 0.2, 0.3), Vec3(3, 0.8, 0.6));
  CHECK(depth_along(a, b, Vec3(-1, 1e-7, 2e-7)) == Approx(0.3).margin(1e-6));
  CHECK(depth_along(a, b, Vec3(1e-7, 1, 2e-7)) == Approx(0.8).margin(1e-6));   // up past the bar: 1 - 0.2
  CHECK(depth_along(a, b, Vec3(2e-7, 1e-7, -1)) == Approx(0.7).margin(1e-6));  // down below it: 1 - 0.3
  // Touching: 0 along any direction that leaves.
  const Mesh t = box_mesh(Vec3(1, 0, 0), Vec3(2, 1, 1));
  CHECK(depth_along(a, t, Vec3(-1, 1e-7, 1e-7)) == 0.0);
  // A concave case: a ring whose tube a post pierces must be lifted clear of the post's top.
  const Mesh post = box_mesh(Vec3(1.8, -0.2, -3), Vec3(2.2, 0.2, 3));
  const Mesh ring = depth_classes()[3].scene.objects[0].mesh;  // torus R 2, r 0.5 around the z axis
  CHECK(depth_along(ring, post, Vec3(1e-7, 2e-7, 1)) == Approx(3.5).margin(1e-6));
}

TEST_CASE("depth: an open object has none, and says why", "[depth]") {
  Mesh open = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  open.triangles.pop_back();
  const PenetrationDepth pd = penetration_depth(open, box_mesh(Vec3(0.5, 0.5, 0.5), Vec3(2, 2, 2)), {});
  CHECK_FALSE(pd.known);
  CHECK(pd.reason.find("open") != std::string::npos);
}

TEST_CASE("proximity on the depth classes: every listed distance is the exact one (relative 1e-9), none missed", "[depth][proximity]") {
  using EK = CGAL::Exact_predicates_exact_constructions_kernel;
  const auto ep = [](const Vec3& v) { return EK::Point_3(v.x(), v.y(), v.z()); };
  const auto exact_distance = [&](const TriangleCorners& a, const TriangleCorners& b) {
    const EK::Triangle_3 ta(ep(a[0]), ep(a[1]), ep(a[2])), tb(ep(b[0]), ep(b[1]), ep(b[2]));
    if (CGAL::do_intersect(ta, tb)) return 0.0;
    EK::FT best = CGAL::squared_distance(ep(a[0]), tb);
    for (int k = 0; k < 3; ++k) {
      best = std::min(best, CGAL::squared_distance(ep(a[k]), tb));
      best = std::min(best, CGAL::squared_distance(ep(b[k]), ta));
      for (int j = 0; j < 3; ++j)
        best = std::min(best, CGAL::squared_distance(EK::Segment_3(ep(a[k]), ep(a[(k + 1) % 3])),
                                                     EK::Segment_3(ep(b[j]), ep(b[(j + 1) % 3]))));
    }
    return std::sqrt(CGAL::to_double(best));
  };
  const std::vector<DepthClass> classes = depth_classes();
  for (std::size_t i = 0; i < classes.size(); ++i) {
    if (test::stride_skips(i)) continue;
    const DepthClass& c = classes[i];
    INFO(c.scene.name);
    const Mesh& a = c.scene.objects[0].mesh;
    const Mesh& b = c.scene.objects[1].mesh;
    const double margin = 0.02;
    const Proximity p = near_pairs(a, b, margin);  // none for the box deep inside the ball
    for (const NearPair& n : p.pairs) {
      const double e = exact_distance(corners(a, n.tri_a), corners(b, n.tri_b));
      REQUIRE(n.distance == Approx(e).epsilon(1e-9).margin(1e-15));
      REQUIRE(n.distance <= margin);
    }
    // Every colliding pair is listed at distance 0.
    for (const std::uint64_t k : exact_colliding_pairs(a, b)) {
      const auto it = std::find_if(p.pairs.begin(), p.pairs.end(),
                                   [&](const NearPair& n) { return n.tri_a == pair_a(k) && n.tri_b == pair_b(k); });
      REQUIRE(it != p.pairs.end());
      CHECK(it->distance == 0.0);
    }
    if (a.triangles.size() * b.triangles.size() > 100000) continue;  // the brute force below: small classes
    std::size_t within = 0;
    for (std::uint32_t x = 0; x < a.triangles.size(); ++x)
      for (std::uint32_t y = 0; y < b.triangles.size(); ++y) within += exact_distance(corners(a, x), corners(b, y)) <= margin;
    CHECK(p.pairs.size() == within);
  }
}

namespace {

// A fixture mesh scaled to a longest side of 1 and centred at the origin.
Mesh unit_mesh(const std::string& name) {
  Mesh m = load_mesh(std::string(PEELCD_FIXTURES) + "/meshes/" + name);
  const Aabb box = bounds(m);
  const Vec3 c = box.center();
  const double s = 1.0 / box.extent().maxCoeff();
  for (Vec3& v : m.vertices) v = (v - c) * s;
  return m;
}

}  // namespace

TEST_CASE("depth: within 1.05x of a 300-direction search on real meshes at several poses", "[depth]") {
  // Closed fixture meshes (bunny, dragon, fish, kitten, raptor, torus), each scaled to a unit box;
  // B turned and moved so that the two overlap by a fair share. The reference: the least of
  // depth_along() over 300 directions of a Fibonacci lattice. The search must come within 5% of
  // it (it may find less: it searches locally too). Ratios and directions evaluated printed.
  const std::pair<const char*, const char*> pairs[] = {{"kitten_1k5.obj", "fish_2k.obj"},
                                                       {"bunny_3k.obj", "velociraptor.obj"},
                                                       {"torus.obj", "kitten_1k5.obj"},
                                                       {"dragon_3k.obj", "fish_2k.obj"}};
  const Vec3 moves[] = {Vec3(0.35, 0.1, -0.05), Vec3(-0.1, 0.3, 0.25)};
  double worst = 0.0;
  std::size_t case_index = 0;
  for (const auto& [na, nb] : pairs) {
    const Mesh a = unit_mesh(na), b0 = unit_mesh(nb);
    for (int k = 0; k < 2; ++k) {
      if (test::stride_skips(case_index++)) continue;
      const Eigen::Matrix3d R = Eigen::AngleAxisd(0.6 + 0.9 * k, Vec3(1, 2 - k, 3).normalized()).toRotationMatrix();
      Mesh b = b0;
      for (Vec3& v : b.vertices) v = R * v + moves[k];
      const std::vector<Contact> contacts = contacts_of(a, b);
      if (contacts.empty()) continue;
      const PenetrationDepth pd = penetration_depth(a, b, contacts);
      REQUIRE(pd.known);
      double reference = std::numeric_limits<double>::infinity();
      constexpr int kDirections = 300;
      for (int i = 0; i < kDirections; ++i) {
        const double z = 1.0 - 2.0 * (i + 0.5) / kDirections, rho = std::sqrt(1.0 - z * z), phi = i * 2.399963229728653;
        reference = std::min(reference, depth_along(a, b, Vec3(rho * std::cos(phi), rho * std::sin(phi), z)));
      }
      const double ratio = reference > 0.0 ? pd.depth / reference : (pd.depth == 0.0 ? 1.0 : INFINITY);
      worst = std::max(worst, ratio);
      std::printf("depth %s / %s pose %d: %.5f against %.5f over 300 directions (%.3fx), %zu directions, from %s\n", na, nb,
                  k, pd.depth, reference, ratio, pd.directions, pd.source.c_str());
      INFO(na << " / " << nb << " pose " << k);
      CHECK(ratio <= 1.05);
      CHECK(pd.directions <= std::size_t(12 + kDepthGlobalDirections + kDepthStarts * kDepthLocalEvaluations));
    }
  }
  std::printf("depth: the worst ratio to the 300-direction search: %.3f\n", worst);
  CHECK(worst > 0.0);
}

TEST_CASE("depth: an overlap under the rounding bound is crossing with a depth of its bound, never 0", "[depth]") {
  // B's face 4e-16 inside A's: the surfaces cross (exact), by far less than the bound (64 ulps).
  const Mesh a = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = box_mesh(Vec3(1.0 - 4.440892098500626e-16, 0.2, 0.3), Vec3(2, 0.8, 0.7));
  const std::vector<Contact> contacts = contacts_of(a, b);
  REQUIRE(contact_relation(contacts) == Relation::crossing);
  const PenetrationDepth pd = penetration_depth(a, b, contacts);
  REQUIRE(pd.known);
  CHECK(pd.depth > 0.0);
  CHECK(pd.depth <= pd.bound);
  CHECK_FALSE(meeting(translated(a, (pd.depth + 1e-12) * pd.direction), b));
  // Touching boxes keep depth 0.
  const Mesh t = box_mesh(Vec3(1, 0.2, 0.3), Vec3(2, 0.8, 0.7));
  CHECK(penetration_depth(a, t, contacts_of(a, t)).depth == 0.0);
}
