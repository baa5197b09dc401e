#include "peelcd/core/exact/narrow_phase.h"

#include <catch2/catch.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <array>
#include <random>

using namespace peelcd;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

double distance_to_triangle(const Vec3& p, const TriangleCorners& t) {
  const auto c = [](const Vec3& v) { return K::Point_3(v.x(), v.y(), v.z()); };
  return std::sqrt(CGAL::to_double(CGAL::squared_distance(c(p), K::Triangle_3(c(t[0]), c(t[1]), c(t[2])))));
}

// The answer must not depend on the order of either triangle's corners nor on which is first.
bool answer_is_order_invariant(const TriangleCorners& a, const TriangleCorners& b) {
  const bool expected = triangles_intersect(a, b);
  std::array<int, 3> pa = {0, 1, 2};
  do {
    std::array<int, 3> pb = {0, 1, 2};
    do {
      const TriangleCorners x = {a[pa[0]], a[pa[1]], a[pa[2]]};
      const TriangleCorners y = {b[pb[0]], b[pb[1]], b[pb[2]]};
      if (triangles_intersect(x, y) != expected || triangles_intersect(y, x) != expected) return false;
    } while (std::next_permutation(pb.begin(), pb.end()));
  } while (std::next_permutation(pa.begin(), pa.end()));
  return true;
}

struct Case {
  const char* name;
  TriangleCorners a, b;
  bool intersect;
};

}  // namespace

TEST_CASE("hand-made triangle pairs get the exact answer in every vertex order", "[narrow]") {
  const TriangleCorners base = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  const std::vector<Case> cases = {
      // B pierces A's interior.
      {"crossing", base, {Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(1.5, 0.2, 0.3)}, true},
      // B's corner lies on A's interior: touching at a point.
      {"touching at a vertex", base, {Vec3(0.5, 0.5, 0), Vec3(1, 1, 1), Vec3(0, 1, 1)}, true},
      // B's edge lies along A's edge (y = 0), B standing up: touching along a segment.
      {"touching along an edge", base, {Vec3(0.5, 0, 0), Vec3(1.5, 0, 0), Vec3(1, 0, 1)}, true},
      // Sharing a whole edge, folded: the shared edge is the intersection.
      {"sharing an edge", base, {Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(1, 1, 1)}, true},
      {"coplanar overlap", base, {Vec3(0.5, 0.5, 0), Vec3(3, 0.5, 0), Vec3(0.5, 3, 0)}, true},
      {"coplanar disjoint", base, {Vec3(1.5, 1.5, 0), Vec3(3, 1.5, 0), Vec3(1.5, 3, 0)}, false},
      {"parallel, 1e-12 apart", base, {Vec3(0, 0, 1e-12), Vec3(2, 0, 1e-12), Vec3(0, 2, 1e-12)}, false},
      {"disjoint, just past the corner", base, {Vec3(2 + 1e-9, 0, -1), Vec3(2 + 1e-9, 0, 1), Vec3(3, 0, 0)}, false},
      {"degenerate: collinear B crossing A", base, {Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 1)}, true},
      {"degenerate: collinear B beside A", base, {Vec3(3, 3, -1), Vec3(3, 3, 0), Vec3(3, 3, 1)}, false},
      {"degenerate: point B on A", base, {Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 0), Vec3(0.5, 0.5, 0)}, true},
      {"degenerate: point B off A", base, {Vec3(0.5, 0.5, 1e-15), Vec3(0.5, 0.5, 1e-15), Vec3(0.5, 0.5, 1e-15)}, false},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    CHECK(triangles_intersect(c.a, c.b) == c.intersect);
    CHECK(answer_is_order_invariant(c.a, c.b));
    if (c.intersect) {
      const auto [p, q] = intersection_segment(c.a, c.b);
      // The segment lies on both triangles up to rounding of its construction (coordinates ~1).
      CHECK(distance_to_triangle(p, c.a) < 1e-12);
      CHECK(distance_to_triangle(q, c.a) < 1e-12);
      CHECK(distance_to_triangle(p, c.b) < 1e-12);
      CHECK(distance_to_triangle(q, c.b) < 1e-12);
    }
  }
}

TEST_CASE("the crossing segment is the chord of the two triangles", "[narrow]") {
  // A in z = 0; B in the plane x = 0.5 crossing A along x = 0.5, y in [0, 1.5].
  const TriangleCorners a = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  const TriangleCorners b = {Vec3(0.5, -1, -1), Vec3(0.5, 5, -1), Vec3(0.5, -1, 5)};
  REQUIRE(triangles_intersect(a, b));
  auto [p, q] = intersection_segment(a, b);
  if (p.y() > q.y()) std::swap(p, q);
  CHECK((p - Vec3(0.5, 0, 0)).norm() < 1e-12);
  CHECK((q - Vec3(0.5, 1.5, 0)).norm() < 1e-12);
}

TEST_CASE("narrow_phase keeps the colliding candidates in candidate order", "[narrow]") {
  Mesh a, b;
  a.vertices = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(10, 0, 0), Vec3(12, 0, 0), Vec3(10, 2, 0)};
  a.triangles = {{0, 1, 2}, {3, 4, 5}};
  b.vertices = {Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(1.5, 0.2, 0.3)};
  b.triangles = {{0, 1, 2}};
  std::vector<Contact> out;
  narrow_phase(a, b, {(std::uint64_t(0) << 32) | 0, (std::uint64_t(1) << 32) | 0}, out);
  REQUIRE(out.size() == 1);
  CHECK(out[0].tri_a == 0);
  CHECK(out[0].tri_b == 0);
}

TEST_CASE("sort_contacts orders sets of any size by (tri_a, tri_b), each contact moved whole", "[narrow]") {
  // Sizes on both sides of kRadixContacts and of the radix sort's change of digit (2,048); indices that fit one key word with the places (the
  // radix path) and indices up to 2^32 - 1 (the comparison sort); repeated couples kept in
  // their input order.
  std::mt19937 rng(7);
  for (const std::size_t n : {std::size_t(5), kRadixContacts - 1, kRadixContacts, std::size_t(228), std::size_t(2047),
                              std::size_t(2048), std::size_t(5000), std::size_t(70000)}) {
    for (const std::uint32_t range : {std::uint32_t(300), std::uint32_t(1) << 21, std::uint32_t(0xffffffffu)}) {
      std::vector<Contact> contacts(n);
      for (std::size_t i = 0; i < n; ++i) {
        contacts[i].tri_a = std::uint32_t(rng() % (std::uint64_t(range) + 1));
        contacts[i].tri_b = i % 7 == 3 && i > 0 ? contacts[i - 1].tri_b : std::uint32_t(rng() % (std::uint64_t(range) + 1));
        if (i % 7 == 3 && i > 0) contacts[i].tri_a = contacts[i - 1].tri_a;  // a repeated couple
        contacts[i].p = Vec3(double(i), 0, 0);  // its place in the input
        contacts[i].q = Vec3(0, double(contacts[i].tri_a), double(contacts[i].tri_b));
        contacts[i].kind = i % 2 ? ContactKind::touching : ContactKind::crossing;
      }
      std::vector<Contact> expected = contacts;
      std::stable_sort(expected.begin(), expected.end(), [](const Contact& x, const Contact& y) {
        return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
      });
      ContactSortScratch scratch;
      for (int round = 0; round < 2; ++round) {  // the scratch reused
        std::vector<Contact> got = contacts;
        if (round == 0)
          sort_contacts(got);
        else
          sort_contacts(got, scratch);
        INFO("n " << n << ", indices up to " << range << ", round " << round);
        REQUIRE(got.size() == n);
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < n; ++i) {
          const Contact& g = got[i];
          const Contact& e = expected[i];
          // Couples repeated in the input may come in either order from the comparison sort;
          // the fields travel with their contact in any case.
          wrong += g.tri_a != e.tri_a || g.tri_b != e.tri_b || g.q != Vec3(0, double(g.tri_a), double(g.tri_b)) ||
                   (g.kind == ContactKind::touching) != (std::size_t(g.p.x()) % 2 == 1);
        }
        CHECK(wrong == 0);
      }
      // Contacts in order already stay as they are (the early return), fields and all.
      std::vector<Contact> again = expected;
      sort_contacts(again, scratch);
      std::size_t moved = 0;
      for (std::size_t i = 0; i < n; ++i) moved += again[i].p != expected[i].p;
      CHECK(moved == 0);
    }
  }
}
