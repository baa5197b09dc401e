#pragma once
// Exact triangle/triangle tests. The yes/no answer uses CGAL's exact predicates
// (Exact_predicates_inexact_constructions_kernel), so it does not depend on vertex order,
// triangle order or rounding. Degenerate triangles (collinear or repeated vertices) are tested
// as the segment or point they are. The intersection segment is constructed in double.
#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/pairs.h"

#include <array>
#include <cstdint>
#include <vector>

namespace peelcd {

bool triangles_intersect(const TriangleCorners& a, const TriangleCorners& b);
// True when both triangles lie in one axis-aligned plane (one coordinate the same double in all
// six corners) and an edge of either separates them in it, every orientation certified in
// double; false otherwise (apart or not, the exact predicates decide). A flat sheet's
// neighbours are all coplanar, where CGAL's filters fail and its exact arithmetic is slow.
bool coplanar_apart(const TriangleCorners& a, const TriangleCorners& b);
// True when a plane through an edge of either triangle, perpendicular to that triangle, has the
// triangle on one side and the other triangle's three corners strictly on the other, every side
// certified in double (a sufficient condition for disjoint triangles in any position; it decides
// nearly coplanar neighbours, whose orientations the certified signs leave to exact arithmetic).
bool apart_across_an_edge(const TriangleCorners& a, const TriangleCorners& b);

// Kind of contact of two intersecting triangles (undefined if they are disjoint).
ContactKind classify_contact(const TriangleCorners& a, const TriangleCorners& b);

// Segment of the intersection of two intersecting triangles. For a coplanar overlap (a
// polygon) it is the polygon's longest chord among its vertices. Undefined if they are disjoint.
std::pair<Vec3, Vec3> intersection_segment(const TriangleCorners& a, const TriangleCorners& b);

// The exact test of one couple of triangles (world corners): true when they share a point, with
// the contact's segment and kind filled in (its triangle indices are the caller's). The same
// test narrow_phase() runs on each candidate.
bool test_triangle_pair(const TriangleCorners& a, const TriangleCorners& b, Contact& contact);
// The same exact yes/no without the segment and kind (cheaper where the triangles meet).
bool triangles_meet(const TriangleCorners& a, const TriangleCorners& b);

// The test of one run of couples (an object pair's, a task's) as DetectOptions::contacts asks:
// every contact with its segment and kind (segments), or (pairs) classified until the run's
// first crossing contact and unclassified after it (kind unclassified, segment 0): a pair's
// relation needs one crossing contact, or, with none, every contact's kind
// (contact_relation(), touching_relation()).
// Signs of one triangle's corners against the other's plane already certified (a block's planes'
// test, core/exact/apart_block.h): b[k], B's corner k against A's plane (+1, -1; 0 only where
// not certified), valid when b_known; a[k], A's against B's, when a_known. Exactly the signs the
// test would certify itself.
struct KnownSides {
  std::int8_t b[3] = {0, 0, 0}, a[3] = {0, 0, 0};
  bool b_known = false, a_known = false;
};

struct ContactTest {
  ContactDetail detail = ContactDetail::segments;
  bool crossing_seen = false;
  // true when the triangles share a point, `contact` filled as said (its indices are the caller's).
  bool operator()(const TriangleCorners& a, const TriangleCorners& b, Contact& contact);
  // The same with the signs `sides` holds (the same answer, fewer operations).
  bool operator()(const TriangleCorners& a, const TriangleCorners& b, Contact& contact, const KnownSides& sides);
};


// Tests every candidate pair (packed with pack_pair(triA, triB), peelcd/core/pairs.h) and appends
// the colliding ones to `out` in candidate order. boxes_overlap: every candidate is known to be
// a pair of overlapping triangle boxes (box_overlap_pairs()'s output), so that first test is
// skipped; the answer is the same either way.
// max_contacts > 0: stops once `out` has gained that many (DetectOptions::max_contacts).
// detail: what each contact holds (ContactTest; DetectOptions::contacts).
void narrow_phase(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates,
                  std::vector<Contact>& out, bool boxes_overlap = false, std::size_t max_contacts = 0,
                  ContactDetail detail = ContactDetail::segments);

}  // namespace peelcd
