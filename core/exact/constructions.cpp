// The constructions of the exact narrow phase: a contact's segment (in double where it is well
// conditioned, exactly otherwise) and its kind.
#include "certified.h"
#include "exact_kernel.h"

#include <CGAL/Cartesian_converter.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <vector>

namespace peelcd {
namespace exact_detail {
namespace {

// Appends every point of an exact-kernel intersection result to `pts`, rounded to double.
struct Collect {
  std::vector<Vec3>& pts;
  // Rounded from the exact value: CGAL's to_double on a lazy number may return its interval
  // approximation when that is within a relative 1e-5, which is far too coarse at large offsets.
  static double round(const EK::FT& x) { return CGAL::to_double(CGAL::exact(x)); }
  static Vec3 to_eigen(const EK::Point_3& p) { return Vec3(round(p.x()), round(p.y()), round(p.z())); }
  void operator()(const EK::Point_3& p) const { pts.push_back(to_eigen(p)); }
  void operator()(const EK::Segment_3& s) const {
    pts.push_back(to_eigen(s.source()));
    pts.push_back(to_eigen(s.target()));
  }
  void operator()(const EK::Triangle_3& t) const {
    for (int i = 0; i < 3; ++i) pts.push_back(to_eigen(t.vertex(i)));
  }
  void operator()(const std::vector<EK::Point_3>& poly) const {
    for (const EK::Point_3& p : poly) pts.push_back(to_eigen(p));
  }
};

template <class A, class B>
void collect_exact(const A& a, const B& b, std::vector<Vec3>& pts) {
  if (auto r = CGAL::intersection(a, b)) boost::apply_visitor(Collect{pts}, *r);
}
// A segment crossing a triangle's plane meets it in one point: the segment's line cut by the
// plane, constructed exactly. (CGAL 5.5's Segment_3 x Triangle_3 construction returned a point
// off the segment for a case the soak found, so it is used only for the coplanar case.)
void collect_exact(const EK::Segment_3& s, const EK::Triangle_3& t, std::vector<Vec3>& pts) {
  const EK::Plane_3 plane = t.supporting_plane();
  if (!plane.has_on(s.source()) || !plane.has_on(s.target())) {
    if (auto r = CGAL::intersection(s.supporting_line(), plane))
      if (const auto* p = boost::get<EK::Point_3>(&*r)) {
        Collect{pts}(*p);
        return;
      }
  }
  if (auto r = CGAL::intersection(s, t)) boost::apply_visitor(Collect{pts}, *r);
}
void collect_exact(const EK::Triangle_3& t, const EK::Segment_3& s, std::vector<Vec3>& pts) { collect_exact(s, t, pts); }
void collect_exact(const EK::Point_3& a, const EK::Point_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Point_3& a, const EK::Segment_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Segment_3&, const EK::Point_3& b, std::vector<Vec3>& pts) { Collect{pts}(b); }
void collect_exact(const EK::Point_3& a, const EK::Triangle_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Triangle_3&, const EK::Point_3& b, std::vector<Vec3>& pts) { Collect{pts}(b); }

// The part of triangle `t` on the plane n.x = c of the other triangle, as the two extreme points
// along `dir`. Which corners lie on, above or below the plane is `side` (exact orientation
// predicates, plane_sides()); only the crossing points of straddling edges are interpolated in
// double (with the plane n.x = c), clamped to their edge. Returns false if the triangle does not reach the plane,
// or if a straddling edge is too close to parallel to it for double to place the crossing.
bool cut_by_plane(const TriangleCorners& t, const int side[3], const Vec3& n, double c, const Vec3& dir, Vec3& lo,
                  Vec3& hi) {
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = n.dot(t[i]) - c;
  Vec3 pts[6];
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (side[i] == 0) pts[count++] = t[i];
    if (side[i] != 0 && side[j] != 0 && side[i] != side[j]) {
      // An edge nearly parallel to the plane (both ends within rounding of it) has no
      // well-defined crossing point in double: leave it to the exact construction.
      const double denom = d[i] - d[j];  // |denom| > 1e-6 |n| |edge|, in squares (no root)
      if (!(denom * denom > 1e-12 * n.squaredNorm() * (t[j] - t[i]).squaredNorm())) return false;
      pts[count++] = t[i] + (t[j] - t[i]) * std::clamp(d[i] / denom, 0.0, 1.0);
    }
  }
  if (count == 0) return false;
  lo = hi = pts[0];
  for (int k = 1; k < count; ++k) {
    if (pts[k].dot(dir) < lo.dot(dir)) lo = pts[k];
    if (pts[k].dot(dir) > hi.dot(dir)) hi = pts[k];
  }
  return true;
}

// The exact piece of the planes' line that triangle `t` (its corners' signs `s` against the
// other's plane, not all zero) covers: its corners on that plane and its edges' crossings of it,
// the extreme two in lexicographic order (all lie on one line, so that order runs along it).
std::pair<EK::Point_3, EK::Point_3> line_piece(const TriangleCorners& t, const int s[3], const TriangleCorners& other) {
  const CGAL::Cartesian_converter<K, EK> to_exact;
  const EK::Plane_3 plane(to_exact(to_cgal(other[0])), to_exact(to_cgal(other[1])), to_exact(to_cgal(other[2])));
  EK::Point_3 pts[4];
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (s[i] == 0) pts[count++] = to_exact(to_cgal(t[i]));
    if (s[i] * s[j] < 0) {
      const EK::Line_3 line(to_exact(to_cgal(t[i])), to_exact(to_cgal(t[j])));
      if (auto r = CGAL::intersection(line, plane))
        if (const auto* p = boost::get<EK::Point_3>(&*r)) pts[count++] = *p;
    }
  }
  EK::Point_3 lo = pts[0], hi = pts[0];
  for (int k = 1; k < count; ++k) {
    if (CGAL::compare_xyz(pts[k], lo) == CGAL::SMALLER) lo = pts[k];
    if (CGAL::compare_xyz(pts[k], hi) == CGAL::LARGER) hi = pts[k];
  }
  return {lo, hi};
}

// Two proper triangles in two planes, each with corners strictly on both sides of the other's
// plane, meet in a piece of the planes' line: where it lies in both, decided exactly from the two
// triangles' pieces of the line (line_piece()). The overlap of the two triangles' pieces of the planes' line (empty when lo comes after hi).
std::pair<EK::Point_3, EK::Point_3> line_overlap(const TriangleCorners& a, const TriangleCorners& b, const int sa[3],
                                                 const int sb[3]) {
  const auto [lo_a, hi_a] = line_piece(a, sa, b);
  const auto [lo_b, hi_b] = line_piece(b, sb, a);
  return {CGAL::compare_xyz(lo_a, lo_b) == CGAL::LARGER ? lo_a : lo_b,
          CGAL::compare_xyz(hi_a, hi_b) == CGAL::SMALLER ? hi_a : hi_b};
}

}  // namespace

Simplex simplex(const TriangleCorners& t) {
  const P3 a = to_cgal(t[0]), b = to_cgal(t[1]), c = to_cgal(t[2]);
  if (!CGAL::collinear(a, b, c)) return T3(a, b, c);
  if (a == b && b == c) return a;
  // Collinear: the segment between the two extreme points. Comparing along the line is exact
  // with lexicographic order, since collinear points are ordered the same on every axis.
  P3 lo = a, hi = a;
  for (const P3& p : {b, c}) {
    if (CGAL::compare_xyz(p, lo) == CGAL::SMALLER) lo = p;
    if (CGAL::compare_xyz(p, hi) == CGAL::LARGER) hi = p;
  }
  return S3(lo, hi);
}

// Segment of two crossing, non-coplanar triangles in double: each triangle cut by the other's
// plane gives a segment on the common line; the intersection is their overlap. sa: A's corners
// against B's plane, sb: B's against A's.
bool crossing_segment(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3], Vec3& p,
                      Vec3& q) {
  const Vec3 a1 = a[1] - a[0], a2 = a[2] - a[0], b1 = b[1] - b[0], b2 = b[2] - b[0];
  const Vec3 na = a1.cross(a2), nb = b1.cross(b2);
  // The double construction is ill-conditioned for planes within 1e-6 rad of parallel, and
  // for needles (an angle under 1e-6 rad), whose normals rounding can turn anywhere.
  // Compared in squares (no roots), whose products reach the eighth power of the triangles'
  // extent: outside 1e-30 .. 1e30 that could leave double's normal range, and the exact
  // construction is used instead.
  const double extent = std::max({a1.cwiseAbs().maxCoeff(), a2.cwiseAbs().maxCoeff(), b1.cwiseAbs().maxCoeff(),
                                  b2.cwiseAbs().maxCoeff()});
  if (!(extent > 1e-30 && extent < 1e30)) return false;
  const double na2 = na.squaredNorm(), nb2 = nb.squaredNorm();
  const Vec3 dir = na.cross(nb);
  const bool steep_enough = na2 > 1e-12 * a1.squaredNorm() * a2.squaredNorm() &&
                            nb2 > 1e-12 * b1.squaredNorm() * b2.squaredNorm() && dir.squaredNorm() > 1e-12 * na2 * nb2;
  if (!steep_enough) return false;
  if (!(dir.squaredNorm() > 0.0)) return false;
  Vec3 alo, ahi, blo, bhi;
  if (!cut_by_plane(a, sa, nb, nb.dot(b[0]), dir, alo, ahi) || !cut_by_plane(b, sb, na, na.dot(a[0]), dir, blo, bhi))
    return false;
  p = alo.dot(dir) > blo.dot(dir) ? alo : blo;  // the later start
  q = ahi.dot(dir) < bhi.dot(dir) ? ahi : bhi;  // the earlier end
  if (p.dot(dir) > q.dot(dir)) p = q = 0.5 * (p + q);  // a touch, split by rounding
  return true;
}

bool meet_in_one_point(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3]) {
  const auto [lo, hi] = line_overlap(a, b, sa, sb);
  return lo == hi;
}

// The segment of two proper triangles in two planes that meet (sa: A's corners against B's
// plane, sb: B's against A's, neither all zero), constructed exactly and rounded once: the
// overlap of their pieces of the planes' line: the points CGAL's triangle/triangle intersection
// gives, without its general construction. False when the pieces do not overlap (the triangles
// do not meet).
bool exact_crossing_segment(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3],
                            Vec3& p, Vec3& q) {
  const auto [lo, hi] = line_overlap(a, b, sa, sb);
  if (CGAL::compare_xyz(lo, hi) == CGAL::LARGER) return false;
  p = Collect::to_eigen(lo);
  q = Collect::to_eigen(hi);
  return true;
}

// The exact construction of the intersection of two simplices: its extreme points.
std::pair<Vec3, Vec3> exact_segment(const TriangleCorners& a, const TriangleCorners& b, const Simplex& sa,
                                    const Simplex& sb) {
  const CGAL::Cartesian_converter<K, EK> to_exact;
  std::vector<Vec3> pts;
  std::visit([&](const auto& x, const auto& y) { collect_exact(to_exact(x), to_exact(y), pts); }, sa, sb);
  if (pts.empty()) {
    // Inexact constructions can fail on a pair the exact predicate calls intersecting (a
    // graze at rounding level); report the nearest corner of A to B's centroid as the point.
    const Vec3 cb = (b[0] + b[1] + b[2]) / 3.0;
    Vec3 best = a[0];
    for (const Vec3& p : a)
      if ((p - cb).squaredNorm() < (best - cb).squaredNorm()) best = p;
    return {best, best};
  }
  std::pair<Vec3, Vec3> seg{pts[0], pts[0]};
  double best = -1.0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i; j < pts.size(); ++j) {
      const double d = (pts[i] - pts[j]).squaredNorm();
      if (d > best) {
        best = d;
        seg = {pts[i], pts[j]};
      }
    }
  return seg;
}

}  // namespace exact_detail

using namespace exact_detail;

ContactKind classify_contact(const TriangleCorners& a, const TriangleCorners& b) {
  const P3 pa[3] = {to_cgal(a[0]), to_cgal(a[1]), to_cgal(a[2])};
  const P3 pb[3] = {to_cgal(b[0]), to_cgal(b[1]), to_cgal(b[2])};
  if (CGAL::collinear(pa[0], pa[1], pa[2]) || CGAL::collinear(pb[0], pb[1], pb[2])) return ContactKind::degenerate;
  // Which sides of `plane` the corners of `t` are on: bit 0 = negative, bit 1 = positive.
  const auto sides = [](const P3* plane, const P3* t) {
    int s = 0;
    for (int i = 0; i < 3; ++i) {
      const CGAL::Orientation o = CGAL::orientation(plane[0], plane[1], plane[2], t[i]);
      if (o == CGAL::NEGATIVE) s |= 1;
      if (o == CGAL::POSITIVE) s |= 2;
    }
    return s;
  };
  const int sb = sides(pa, pb), sa = sides(pb, pa);
  if (sb == 0) return ContactKind::coplanar;  // every corner of B on A's plane
  if (sa != 3 || sb != 3) return ContactKind::touching;
  // Each straddles the other's plane: crossing, unless they meet in one point only.
  int side_a[3], side_b[3];
  for (int i = 0; i < 3; ++i) {
    side_a[i] = int(CGAL::orientation(pb[0], pb[1], pb[2], pa[i]));
    side_b[i] = int(CGAL::orientation(pa[0], pa[1], pa[2], pb[i]));
  }
  return meet_in_one_point(a, b, side_a, side_b) ? ContactKind::touching : ContactKind::crossing;
}

std::pair<Vec3, Vec3> intersection_segment(const TriangleCorners& a, const TriangleCorners& b) {
  const Simplex sa = simplex(a), sb = simplex(b);
  // Common case: two proper triangles crossing, not coplanar: constructed in double.
  if (std::holds_alternative<T3>(sa) && std::holds_alternative<T3>(sb)) {
    int side_a[3], side_b[3];
    plane_sides(b, a, side_a);
    plane_sides(a, b, side_b);
    Vec3 p, q;
    if (!all_zero(side_b) && crossing_segment(a, b, side_a, side_b, p, q)) return {p, q};
  }
  // Coplanar overlaps, degenerate triangles, and grazes that rounding lost: exact constructions.
  return exact_segment(a, b, sa, sb);
}

}  // namespace peelcd
