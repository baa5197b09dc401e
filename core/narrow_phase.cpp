#include "peelcd/core/narrow_phase.h"

#include "peelcd/core/aabb.h"

#include "peelcd/core/id_map.h"

#include <CGAL/Cartesian_converter.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <iterator>

#include <variant>

namespace peelcd {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using P3 = K::Point_3;
using S3 = K::Segment_3;
using T3 = K::Triangle_3;

P3 to_cgal(const Vec3& p) { return P3(p.x(), p.y(), p.z()); }

// A triangle as the simplex it really is: triangle, segment (collinear) or point (all equal).
using Simplex = std::variant<T3, S3, P3>;

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

bool intersect(const P3& a, const P3& b) { return a == b; }
bool intersect(const S3& s, const P3& p) { return s.has_on(p); }
bool intersect(const P3& p, const S3& s) { return s.has_on(p); }
bool intersect(const T3& t, const P3& p) { return t.has_on(p); }
bool intersect(const P3& p, const T3& t) { return t.has_on(p); }
template <class A, class B>
bool intersect(const A& a, const B& b) {
  return CGAL::do_intersect(a, b);
}

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

// Shewchuk's orient3d error bound (Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates, 1997): with eps = 2^-53, |det - exact| <= (7 + 56 eps) eps * permanent
// when nothing overflows or underflows. The absolute term covers underflow; an overflow gives
// inf or NaN, which no comparison below accepts.
constexpr double kOrient3dBound = (7.0 + 56.0 * 1.1102230246251565e-16) * 1.1102230246251565e-16;
constexpr double kUnderflowSlack = 1e-290;

// The sign of orient3d(p, q, r, d) when the double evaluation certifies it: +1, -1, or 0 when it
// cannot (then the exact predicates decide).
int certain_orientation(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& d) {
  const double adx = p.x() - d.x(), bdx = q.x() - d.x(), cdx = r.x() - d.x();
  const double ady = p.y() - d.y(), bdy = q.y() - d.y(), cdy = r.y() - d.y();
  const double adz = p.z() - d.z(), bdz = q.z() - d.z(), cdz = r.z() - d.z();
  const double bc = bdy * cdz - bdz * cdy, ca = cdy * adz - cdz * ady, ab = ady * bdz - adz * bdy;
  const double det = adx * bc + bdx * ca + cdx * ab;
  const double permanent = (std::fabs(bdy * cdz) + std::fabs(bdz * cdy)) * std::fabs(adx) +
                           (std::fabs(cdy * adz) + std::fabs(cdz * ady)) * std::fabs(bdx) +
                           (std::fabs(ady * bdz) + std::fabs(adz * bdy)) * std::fabs(cdx);
  const double bound = kOrient3dBound * permanent + kUnderflowSlack;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return 0;
}

// CGAL's orientation(p, q, r, s) as -1, 0, +1 (positive: s on the positive side of the oriented
// plane pqr): certified in double where the bound allows (Shewchuk's det has the opposite sign),
// CGAL's exact predicate otherwise.
int orientation_sign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const int certain = certain_orientation(p, q, r, s);
  if (certain != 0) return -certain;
  return int(CGAL::orientation(to_cgal(p), to_cgal(q), to_cgal(r), to_cgal(s)));
}

// The axis (0, 1, 2) whose coordinate is the same double in the three corners of `a` (and of
// `b` when given: both triangles in one axis-aligned plane, exactly), or -1.
int axis_plane(const TriangleCorners& a, const TriangleCorners* b = nullptr) {
  for (int k = 0; k < 3; ++k) {
    const double c = a[0][k];
    if (a[1][k] == c && a[2][k] == c && (!b || ((*b)[0][k] == c && (*b)[1][k] == c && (*b)[2][k] == c))) return k;
  }
  return -1;
}

// Shewchuk's orient2d bound: |det - exact| <= (3 + 16 eps) eps (|left| + |right|), eps = 2^-53.
constexpr double kOrient2dBound = (3.0 + 16.0 * 1.1102230246251565e-16) * 1.1102230246251565e-16;

// The sign of orient2d(p, q, r) in the coordinates (u, v) when the double evaluation certifies
// it, else 0 (too close to call, or a product under- or overflowing).
int certain_orientation_2d(const Vec3& p, const Vec3& q, const Vec3& r, int u, int v) {
  const double left = (p[u] - r[u]) * (q[v] - r[v]), right = (p[v] - r[v]) * (q[u] - r[u]);
  const double det = left - right;
  const double bound = kOrient2dBound * (std::fabs(left) + std::fabs(right)) + kUnderflowSlack;
  return (det > bound) - (det < -bound);
}

// The signs of the corners of `t` against the plane of `plane` (orientation_sign()): the same
// determinant expanded about plane[0], det(q - p, r - p, d - p) = (d - p) . ((q - p) x (r - p)),
// whose 2x2 minors (and their magnitudes) are computed once for the three corners. It is
// Shewchuk's orient3d with p as the common point (three rounded differences, 2x2 products, one
// 3-term sum: his error bound applies as it stands). A plane along a coordinate axis decides
// the rest exactly. Returns false when a sign is left at 0 uncertified (exact_plane_sides()
// decides those).
bool certain_plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
  const Vec3& p = plane[0];
  const double e1x = plane[1].x() - p.x(), e1y = plane[1].y() - p.y(), e1z = plane[1].z() - p.z();
  const double e2x = plane[2].x() - p.x(), e2y = plane[2].y() - p.y(), e2z = plane[2].z() - p.z();
  const double cx = e1y * e2z - e1z * e2y, cy = e1z * e2x - e1x * e2z, cz = e1x * e2y - e1y * e2x;
  const double mx = std::fabs(e1y * e2z) + std::fabs(e1z * e2y), my = std::fabs(e1z * e2x) + std::fabs(e1x * e2z),
               mz = std::fabs(e1x * e2y) + std::fabs(e1y * e2x);
  // The certified signs without a branch on them (which side a corner lies on follows the
  // geometry, which no branch predictor learns).
  int certain = 1;
  for (int i = 0; i < 3; ++i) {
    const double fx = t[i].x() - p.x(), fy = t[i].y() - p.y(), fz = t[i].z() - p.z();
    const double det = fx * cx + fy * cy + fz * cz;
    const double bound = kOrient3dBound * (std::fabs(fx) * mx + std::fabs(fy) * my + std::fabs(fz) * mz) + kUnderflowSlack;
    const int above = det > bound, below = det < -bound;
    side[i] = above - below;
    certain &= above | below;
  }
  if (__builtin_expect(certain, 1)) return true;
  // A plane of constant coordinate k (a flat sheet, a face resting on a floor): its normal is
  // exactly along k, so a corner's side is the sign of its k offset (exact) times the sign of
  // the triangle's orientation in the other two coordinates (certified in double when it can
  // be). The corners exactly on such a plane, which every filter leaves to exact arithmetic,
  // cost nothing then.
  if (const int k = axis_plane(plane); k >= 0) {
    const int turn = certain_orientation_2d(plane[0], plane[1], plane[2], (k + 1) % 3, (k + 2) % 3);
    if (turn != 0) {
      const double c = plane[0][k];
      for (int i = 0; i < 3; ++i) side[i] = ((t[i][k] > c) - (t[i][k] < c)) * turn;
      return true;
    }
  }
  return false;
}

// The sides certain_plane_sides() left at 0, decided by CGAL (exact; rare, and slow).
void exact_plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
  for (int i = 0; i < 3; ++i)
    if (side[i] == 0)
      side[i] = int(CGAL::orientation(to_cgal(plane[0]), to_cgal(plane[1]), to_cgal(plane[2]), to_cgal(t[i])));
}

void plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
  if (!certain_plane_sides(plane, t, side)) exact_plane_sides(plane, t, side);
}

bool all_zero(const int s[3]) { return s[0] == 0 && s[1] == 0 && s[2] == 0; }
bool one_open_side(const int s[3]) { return s[0] != 0 && s[0] == s[1] && s[1] == s[2]; }

// The part of triangle `t` on the plane n.x = c of the other triangle, as the two extreme points
// along `dir`. Which corners lie on, above or below the plane is `side` (exact orientation
// predicates, plane_sides()); only the crossing points of straddling edges are interpolated in double (with the
// plane n.x = c), clamped to their edge. Returns false if the triangle does not reach the plane,
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

// Guigue and Devillers' test (Fast and Robust Triangle-Triangle Overlap Test Using Orientation
// Predicates, 2003), as CGAL's do_intersect(Triangle_3, Triangle_3) runs it, on the signs already
// known: two proper triangles, not coplanar (neither sign triple all zero), neither strictly on one
// side of the other's plane. Both triangles are turned so that their lone corner (the one on its
// own side of the other's plane) comes first; they meet iff the two intervals they cut on the
// common line overlap, two more orientation predicates.
struct Cut {
  int s_min, t_min, s_max, t_max;
};
Cut lone_corner(const int d[3]) {
  const int p = d[0], q = d[1], r = d[2];
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

bool crossing_intersect(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3]) {
  const Cut c1 = lone_corner(sa), c2 = lone_corner(sb);
  return orientation_sign(a[c1.s_min], a[c1.t_min], b[c2.s_min], b[c2.t_min]) <= 0 &&
         orientation_sign(a[c1.s_max], a[c1.t_max], b[c2.t_max], b[c2.s_max]) <= 0;
}

// Two proper triangles in two planes, each with corners strictly on both sides of the other's
// plane, meet in a piece of the planes' line: where it lies in both. That piece is one point when
// the line leaves one triangle exactly where it enters the other (two side faces of offset boxes
// meeting at a corner of each): the surfaces touch there, they do not cross. Decided exactly:
// each triangle's piece of the line from its edges' exact crossings of the other's plane (and
// its corners on it), ordered along the line lexicographically (as simplex() orders collinear
// points), then the two pieces' overlap.
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
// plane, meet in a piece of the planes' line: where it lies in both. That piece is one point when
// the line leaves one triangle exactly where it enters the other (two side faces of offset boxes
// meeting at a corner of each): the surfaces touch there, they do not cross. Decided exactly
// from the two triangles' pieces of the line and their overlap (line_overlap()).
// The overlap of the two triangles' pieces of the planes' line (empty when lo comes after hi).
std::pair<EK::Point_3, EK::Point_3> line_overlap(const TriangleCorners& a, const TriangleCorners& b, const int sa[3],
                                                 const int sb[3]) {
  const auto [lo_a, hi_a] = line_piece(a, sa, b);
  const auto [lo_b, hi_b] = line_piece(b, sb, a);
  return {CGAL::compare_xyz(lo_a, lo_b) == CGAL::LARGER ? lo_a : lo_b,
          CGAL::compare_xyz(hi_a, hi_b) == CGAL::SMALLER ? hi_a : hi_b};
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

}  // namespace

const char* to_string(ContactKind kind) {
  switch (kind) {
    case ContactKind::crossing: return "crossing";
    case ContactKind::touching: return "touching";
    case ContactKind::coplanar: return "coplanar";
    case ContactKind::degenerate: return "degenerate";
  }
  return "?";
}

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

bool coplanar_apart(const TriangleCorners& a, const TriangleCorners& b) {
  const int k = axis_plane(a, &b);
  if (k < 0) return false;
  const int u = (k + 1) % 3, v = (k + 2) % 3;
  const int ta = certain_orientation_2d(a[0], a[1], a[2], u, v), tb = certain_orientation_2d(b[0], b[1], b[2], u, v);
  if (ta == 0 || tb == 0) return false;  // a triangle without area there, or too thin to tell
  // Closed convex polygons in a plane are apart exactly when the line of some edge has the
  // other polygon strictly on its outer side (the separating axis theorem, edge normals).
  const auto separates = [&](const TriangleCorners& t, int inside, const TriangleCorners& o) {
    for (int e = 0; e < 3; ++e) {
      const Vec3 &p = t[e], &q = t[(e + 1) % 3];
      if (certain_orientation_2d(p, q, o[0], u, v) == -inside && certain_orientation_2d(p, q, o[1], u, v) == -inside &&
          certain_orientation_2d(p, q, o[2], u, v) == -inside)
        return true;
    }
    return false;
  };
  return separates(a, ta, b) || separates(b, tb, a);
}

// apart_across_an_edge(): the side of x of the plane through edge (p, q) of a triangle with
// normal n, perpendicular to the triangle: the sign of (x - p) . ((q - p) x n), a polynomial of
// degree 4 in rounded differences. Its rounding is at most about 12 eps times the same sum of
// products over magnitudes (one eps for each difference, product and sum on the longest path);
// the bound takes 32 eps. The absolute term covers underflow; an overflow gives inf or NaN,
// which no comparison accepts (no side).
constexpr double kEdgePlaneBound = 32.0 * 1.1102230246251565e-16;

bool apart_across_an_edge(const TriangleCorners& a, const TriangleCorners& b) {
  const auto beyond = [](const TriangleCorners& t, const TriangleCorners& o) {
    const Vec3 f1 = t[1] - t[0], f2 = t[2] - t[0];
    const Vec3 n = f1.cross(f2);
    const Vec3 n_mag(std::fabs(f1.y() * f2.z()) + std::fabs(f1.z() * f2.y()),
                     std::fabs(f1.z() * f2.x()) + std::fabs(f1.x() * f2.z()),
                     std::fabs(f1.x() * f2.y()) + std::fabs(f1.y() * f2.x()));
    for (int e = 0; e < 3; ++e) {
      const Vec3& p = t[e];
      const Vec3 d = t[(e + 1) % 3] - p;
      const Vec3 m = d.cross(n);
      const Vec3 m_mag(std::fabs(d.y()) * n_mag.z() + std::fabs(d.z()) * n_mag.y(),
                       std::fabs(d.z()) * n_mag.x() + std::fabs(d.x()) * n_mag.z(),
                       std::fabs(d.x()) * n_mag.y() + std::fabs(d.y()) * n_mag.x());
      const auto side = [&](const Vec3& x) {
        const Vec3 g = x - p;
        const double v = g.dot(m);
        const double bound = kEdgePlaneBound * g.cwiseAbs().dot(m_mag) + kUnderflowSlack;
        return int(v > bound) - int(v < -bound);
      };
      const int inside = side(t[(e + 2) % 3]);  // the triangle's own side (0: too thin to tell)
      if (inside != 0 && side(o[0]) == -inside && side(o[1]) == -inside && side(o[2]) == -inside) return true;
    }
    return false;
  };
  return beyond(a, b) || beyond(b, a);
}

bool triangles_intersect(const TriangleCorners& a, const TriangleCorners& b) {
  // A flat or smooth sheet's neighbours, nearly coplanar: no exact predicate needed where an
  // edge's plane separates them.
  if (coplanar_apart(a, b) || apart_across_an_edge(a, b)) return false;
  const Simplex sa = simplex(a), sb = simplex(b);
  return std::visit([](const auto& x, const auto& y) { return intersect(x, y); }, sa, sb);
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

bool test_triangle_pair(const TriangleCorners& ca, const TriangleCorners& cb, Contact& contact) {
  // The six corner/plane signs, each once (certified in double, exact where double cannot
  // tell); most candidates end here, one triangle strictly on one side of the other's plane.
  // Where a sign is left to exact arithmetic (a corner on or within rounding of the other's
  // plane: a smooth sheet's neighbours), a plane through an edge may separate the two first.
  int side_b[3], side_a[3];
  bool edge_planes_tried = false;
  if (!certain_plane_sides(ca, cb, side_b)) {
    if (apart_across_an_edge(ca, cb)) return false;
    edge_planes_tried = true;
    exact_plane_sides(ca, cb, side_b);
  }
  if (one_open_side(side_b)) return false;
  // B in A's plane (or A without area): coplanar, whatever A's signs against B's plane are.
  const bool coplanar_b = all_zero(side_b);
  if (!coplanar_b) {
    if (!certain_plane_sides(cb, ca, side_a)) {
      if (!edge_planes_tried && apart_across_an_edge(ca, cb)) return false;
      exact_plane_sides(cb, ca, side_a);
    }
    if (one_open_side(side_a)) return false;
  }
  if (coplanar_b || all_zero(side_a)) {
    // Coplanar, or a triangle without area: the general exact test and constructions.
    if (!triangles_intersect(ca, cb)) return false;
    std::tie(contact.p, contact.q) = intersection_segment(ca, cb);
    contact.kind = classify_contact(ca, cb);
    return true;
  }
  // Two proper triangles in two planes (a zero-area triangle has every sign 0 against its own
  // plane): Guigue-Devillers on the signs, the kind from them, the segment in double where it
  // is well conditioned.
  if (!crossing_intersect(ca, cb, side_a, side_b)) return false;
  const auto both = [](const int s[3]) {
    return (s[0] < 0 || s[1] < 0 || s[2] < 0) && (s[0] > 0 || s[1] > 0 || s[2] > 0);
  };
  contact.kind = both(side_a) && both(side_b) ? ContactKind::crossing : ContactKind::touching;
  if (!crossing_segment(ca, cb, side_a, side_b, contact.p, contact.q) &&
      !exact_crossing_segment(ca, cb, side_a, side_b, contact.p, contact.q))
    std::tie(contact.p, contact.q) = exact_segment(ca, cb, simplex(ca), simplex(cb));
  // A crossing whose segment is (near) a point may be two triangles meeting at one point of
  // their boundaries: decided exactly (meet_in_one_point()) only then, so crossings pay nothing.
  if (contact.kind == ContactKind::crossing) {
    const double scale = std::max({ca[0].cwiseAbs().maxCoeff(), ca[1].cwiseAbs().maxCoeff(), ca[2].cwiseAbs().maxCoeff(),
                                   cb[0].cwiseAbs().maxCoeff(), cb[1].cwiseAbs().maxCoeff(), cb[2].cwiseAbs().maxCoeff()});
    if ((contact.p - contact.q).cwiseAbs().maxCoeff() <= 1e-9 * scale + 1e-300 &&
        meet_in_one_point(ca, cb, side_a, side_b))
      contact.kind = ContactKind::touching;
  }
  return true;
}

namespace {
int bit_width(std::uint64_t v) {
  int b = 0;
  for (; v; v >>= 1) ++b;
  return b;
}
}  // namespace

void sort_contacts(std::vector<Contact>& contacts, ContactSortScratch& scratch) {
  const std::size_t n = contacts.size();
  std::uint32_t max_a = 0, max_b = 0;
  if (n >= kRadixContacts)
    for (const Contact& c : contacts) max_a = std::max(max_a, c.tri_a), max_b = std::max(max_b, c.tri_b);
  // A key per contact: (tri_a, tri_b, its place) in one 64-bit word, when they fit.
  const int place_bits = bit_width(n - 1), b_bits = bit_width(max_b), key_bits = bit_width(max_a) + b_bits;
  if (n < kRadixContacts || place_bits + key_bits > 64) {
    std::sort(contacts.begin(), contacts.end(), [](const Contact& x, const Contact& y) {
      return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
    });
    return;
  }
  std::vector<std::uint64_t>& keys = scratch.keys;
  std::vector<std::uint64_t>& spare = scratch.spare;
  keys.resize(n);
  spare.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    keys[i] = (((std::uint64_t(contacts[i].tri_a) << b_bits) | contacts[i].tri_b) << place_bits) | i;
  // Least significant digit first over the index bits (each pass stable): keys in order.
  constexpr int kDigit = 11;
  constexpr std::uint64_t kMask = (1u << kDigit) - 1;
  std::uint32_t count[1u << kDigit];
  for (int shift = place_bits; shift < place_bits + key_bits; shift += kDigit) {
    std::fill(std::begin(count), std::end(count), 0u);
    for (const std::uint64_t k : keys) ++count[(k >> shift) & kMask];
    std::uint32_t sum = 0;
    for (std::uint32_t& c : count) {
      const std::uint32_t here = c;
      c = sum;
      sum += here;
    }
    for (const std::uint64_t k : keys) spare[count[(k >> shift) & kMask]++] = k;
    keys.swap(spare);
  }
  std::vector<Contact>& sorted = scratch.sorted;
  sorted.resize(n);
  const std::uint64_t place = (std::uint64_t(1) << place_bits) - 1;
  for (std::size_t i = 0; i < n; ++i) sorted[i] = contacts[keys[i] & place];
  contacts.swap(sorted);
}

void sort_contacts(std::vector<Contact>& contacts) {
  ContactSortScratch scratch;
  sort_contacts(contacts, scratch);
}

void narrow_phase(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates,
                  std::vector<Contact>& out, bool boxes_overlap, std::size_t max_contacts) {
  const std::size_t limit = max_contacts ? out.size() + max_contacts : std::size_t(-1);
  for (std::uint64_t c : candidates) {
    const std::uint32_t ta = pair_a(c), tb = pair_b(c);
    // A triangle lies in the box of its corners: disjoint boxes, no contact (exact: comparisons
    // of doubles; boxes that only touch overlap). Skipped when the caller's candidates are
    // pairs of overlapping boxes already.
    if (!boxes_overlap && !triangle_bounds(a, ta).overlaps(triangle_bounds(b, tb))) continue;
    Contact contact;
    contact.tri_a = ta;
    contact.tri_b = tb;
    if (test_triangle_pair(corners(a, ta), corners(b, tb), contact)) {
      out.push_back(contact);
      if (out.size() >= limit) return;
    }
  }
}

}  // namespace peelcd
