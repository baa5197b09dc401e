// The exact triangle test (Guigue and Devillers on certified signs, CGAL's exact predicates where
// they cannot tell), the contact sort and the narrow phase over a pair's candidates.
#include "peelcd/core/exact/narrow_phase.h"

#include "apart_block.h"
#include "certified.h"
#include "exact_kernel.h"
#include "peelcd/core/aabb.h"

#include <CGAL/intersections.h>

#include <algorithm>
#include <iterator>
#include <tuple>

namespace peelcd {
namespace {

using namespace exact_detail;

bool intersect(const P3& a, const P3& b) { return a == b; }
bool intersect(const S3& s, const P3& p) { return s.has_on(p); }
bool intersect(const P3& p, const S3& s) { return s.has_on(p); }
bool intersect(const T3& t, const P3& p) { return t.has_on(p); }
bool intersect(const P3& p, const T3& t) { return t.has_on(p); }
template <class A, class B>
bool intersect(const A& a, const B& b) {
  return CGAL::do_intersect(a, b);
}

// Guigue and Devillers' test (Fast and Robust Triangle-Triangle Overlap Test Using Orientation
// Predicates, 2003), as CGAL's do_intersect(Triangle_3, Triangle_3) runs it, on the signs already
// known: two proper triangles, not coplanar (neither sign triple all zero), neither strictly on one
// side of the other's plane. Both triangles are turned so that their lone corner (the one on its
// own side of the other's plane) comes first; they meet iff the two intervals they cut on the
// common line overlap, two more orientation predicates.
struct Cut {
  int s_min, t_min, s_max, t_max;
};
constexpr Cut lone_corner_of(int p, int q, int r) {
  // The corner alone on the positive (closed negative) side gives (i, j, k, i) ((k, i, i, j)).
  const auto pos = [](int i) { return Cut{i, (i + 1) % 3, (i + 2) % 3, i}; };
  const auto neg = [](int i) { return Cut{(i + 2) % 3, i, i, (i + 1) % 3}; };
  if (p > 0) {
    if (q > 0) return neg(2);
    return r > 0 ? neg(1) : pos(0);
  }
  if (p < 0) {
    if (q < 0) return pos(2);
    return r < 0 ? pos(1) : neg(0);
  }
  if (q > 0) return r > 0 ? neg(0) : pos(1);
  if (q < 0) return r < 0 ? pos(0) : neg(1);
  return r > 0 ? pos(2) : neg(2);
}

// lone_corner_of() for each of the 27 sign triples, at (p + 1) * 9 + (q + 1) * 3 + r + 1: the
// crossing test looks its cut up (the branches above, on every candidate that reaches it, are
// mispredicted a quarter of the time in cachegrind's branch model). Signs are -1, 0 or 1.
struct LoneCorners {
  Cut cut[27];
};
constexpr LoneCorners lone_corners() {
  LoneCorners t{};
  for (int p = -1; p <= 1; ++p)
    for (int q = -1; q <= 1; ++q)
      for (int r = -1; r <= 1; ++r) t.cut[(p + 1) * 9 + (q + 1) * 3 + r + 1] = lone_corner_of(p, q, r);
  return t;
}
constexpr LoneCorners kLoneCorners = lone_corners();

Cut lone_corner(const int d[3]) { return kLoneCorners.cut[(d[0] + 1) * 9 + (d[1] + 1) * 3 + d[2] + 1]; }

// Each of the two predicates compares an end of one triangle's interval with an end of the
// other's, and is 0 exactly when those ends coincide: the lines through the two edges it takes
// (each from a lone corner, off the other's plane, to a corner across it) are coplanar iff they
// meet, and two such lines in two distinct planes can meet only on the planes' common line. So
// two triangles whose intervals are proper segments (each with corners strictly on both sides of
// the other's plane) meet in one point iff they meet and one predicate is 0 (`end_to_end`).
bool crossing_intersect(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3],
                        bool& end_to_end) {
  const Cut c1 = lone_corner(sa), c2 = lone_corner(sb);
  const int lo = orientation_sign(a[c1.s_min], a[c1.t_min], b[c2.s_min], b[c2.t_min]);
  if (lo > 0) return false;
  const int hi = orientation_sign(a[c1.s_max], a[c1.t_max], b[c2.t_max], b[c2.s_max]);
  end_to_end = lo == 0 || hi == 0;
  return hi <= 0;
}

}  // namespace


bool triangles_intersect(const TriangleCorners& a, const TriangleCorners& b) {
  // A flat or smooth sheet's neighbours, nearly coplanar: no exact predicate needed where an
  // edge's plane separates them.
  if (coplanar_apart(a, b) || apart_across_an_edge(a, b)) return false;
  const Simplex sa = simplex(a), sb = simplex(b);
  return std::visit([](const auto& x, const auto& y) { return intersect(x, y); }, sa, sb);
}

namespace {

// The test, with the segment and kind (kClassify) or the yes/no alone: one body, so that the two
// answer alike on every couple. Inlined into each entry point, its plane sides too (called out
// of line, they cost the 400-ball pile's frame a few percent).
template <bool kClassify>
PEELCD_ALWAYS_INLINE bool test_pair(const TriangleCorners& ca, const TriangleCorners& cb, Contact& contact,
                                    const KnownSides* known = nullptr) {
  // The six corner/plane signs, each once (certified in double, exact where double cannot
  // tell); most candidates end here, one triangle strictly on one side of the other's plane.
  // Where a sign is left to exact arithmetic (a corner on or within rounding of the other's
  // plane: a smooth sheet's neighbours), a plane through an edge may separate the two first.
  // Signs a block's lanes certified (`known`) are taken as they are: the same values.
  int side_b[3], side_a[3];
  bool edge_planes_tried = false;
  if (known && known->b_known) {
    for (int k = 0; k < 3; ++k) side_b[k] = known->b[k];
  } else if (!certain_plane_sides(ca, cb, side_b)) {
    if (apart_across_an_edge(ca, cb)) return false;
    edge_planes_tried = true;
    exact_plane_sides(ca, cb, side_b);
  }
  if (one_open_side(side_b)) return false;
  // B in A's plane (or A without area): coplanar, whatever A's signs against B's plane are.
  const bool coplanar_b = all_zero(side_b);
  if (!coplanar_b) {
    if (known && known->a_known) {
      for (int k = 0; k < 3; ++k) side_a[k] = known->a[k];
    } else if (!certain_plane_sides(cb, ca, side_a)) {
      if (!edge_planes_tried && apart_across_an_edge(ca, cb)) return false;
      exact_plane_sides(cb, ca, side_a);
    }
    if (one_open_side(side_a)) return false;
  }
  if (coplanar_b || all_zero(side_a)) {
    // Coplanar, or a triangle without area: the general exact test and constructions.
    if (!triangles_intersect(ca, cb)) return false;
    if (!kClassify) return true;
    std::tie(contact.p, contact.q) = intersection_segment(ca, cb);
    contact.kind = classify_contact(ca, cb);
    return true;
  }
  // Two proper triangles in two planes (a zero-area triangle has every sign 0 against its own
  // plane): Guigue-Devillers on the signs, the kind from them, the segment in double where it
  // is well conditioned.
  bool end_to_end = false;
  if (!crossing_intersect(ca, cb, side_a, side_b, end_to_end)) return false;
  if (!kClassify) return true;
  const auto both = [](const int s[3]) {
    return (s[0] < 0 || s[1] < 0 || s[2] < 0) && (s[0] > 0 || s[1] > 0 || s[2] > 0);
  };
  // Crossing: each straddles the other's plane and they share more than one point (two
  // intervals end to end meet at their boundaries only: touching). From the signs alone.
  contact.kind = both(side_a) && both(side_b) && !end_to_end ? ContactKind::crossing : ContactKind::touching;
  if (!crossing_segment(ca, cb, side_a, side_b, contact.p, contact.q) &&
      !exact_crossing_segment(ca, cb, side_a, side_b, contact.p, contact.q))
    std::tie(contact.p, contact.q) = exact_segment(ca, cb, simplex(ca), simplex(cb));
  return true;
}

}  // namespace

bool test_triangle_pair(const TriangleCorners& ca, const TriangleCorners& cb, Contact& contact) {
  return test_pair<true>(ca, cb, contact);
}

bool triangles_meet(const TriangleCorners& a, const TriangleCorners& b) {
  Contact unused;
  return test_pair<false>(a, b, unused);
}

namespace {

PEELCD_ALWAYS_INLINE bool contact_test(ContactTest& t, const TriangleCorners& a, const TriangleCorners& b,
                                       Contact& contact, const KnownSides* known) {
  if (t.detail == ContactDetail::segments || !t.crossing_seen) {
    if (!test_pair<true>(a, b, contact, known)) return false;
    t.crossing_seen |= contact.kind == ContactKind::crossing;
    return true;
  }
  if (!test_pair<false>(a, b, contact, known)) return false;
  contact.p = contact.q = Vec3::Zero();
  contact.kind = ContactKind::unclassified;
  return true;
}

}  // namespace

bool ContactTest::operator()(const TriangleCorners& a, const TriangleCorners& b, Contact& contact) {
  return contact_test(*this, a, b, contact, nullptr);
}

bool ContactTest::operator()(const TriangleCorners& a, const TriangleCorners& b, Contact& contact,
                             const KnownSides& sides) {
  return contact_test(*this, a, b, contact, &sides);
}


void narrow_phase(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates,
                  std::vector<Contact>& out, bool boxes_overlap, std::size_t max_contacts, ContactDetail detail) {
  const std::size_t limit = max_contacts ? out.size() + max_contacts : std::size_t(-1);
  ContactTest test{detail};
  // A block at a time: the couples certainly apart by a plane found in SIMD lanes first
  // (apart_block.h), the rest tested in candidate order.
  ApartBlock block;
  const TestInto test_left{test, out, limit};
  for (std::uint64_t c : candidates) {
    const std::uint32_t ta = pair_a(c), tb = pair_b(c);
    // A triangle lies in the box of its corners: disjoint boxes, no contact (exact: comparisons
    // of doubles; boxes that only touch overlap). Skipped when the caller's candidates are
    // pairs of overlapping boxes already.
    if (!boxes_overlap && !triangle_bounds(a, ta).overlaps(triangle_bounds(b, tb))) continue;
    block.put(ta, tb, corners(a, ta), corners(b, tb));
    if (block.full() && !block.drain(test_left)) return;
  }
  block.drain(test_left);
}

}  // namespace peelcd
