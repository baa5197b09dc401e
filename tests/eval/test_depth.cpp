// Penetration depth (peelcd/core/depth.h) on the depth classes (eval/classes.cpp): moving A by
// (d + 1e-6 of the scene's size) n leaves no intersecting triangle pair and no containment
// (exact), moving it by 0.97 d still overlaps, and the swapped pair gives (-n, d).
#include "peelcd/core/depth.h"
#include "peelcd/core/reference.h"
#include "peelcd/core/relation.h"
#include "peelcd/eval/classes.h"

#include <catch2/catch.hpp>

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

TEST_CASE("depth: moving A by d + 1e-6 of the scene along n separates, by 0.97 d does not; swapped (-n, d)", "[depth]") {
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
