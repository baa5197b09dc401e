#include "core/narrow_phase.h"

#include "core/id_map.h"

#include <CGAL/Cartesian_converter.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <cmath>

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
  static Vec3 to_eigen(const EK::Point_3& p) {
    return Vec3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  }
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
void collect_exact(const EK::Point_3& a, const EK::Point_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Point_3& a, const EK::Segment_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Segment_3&, const EK::Point_3& b, std::vector<Vec3>& pts) { Collect{pts}(b); }
void collect_exact(const EK::Point_3& a, const EK::Triangle_3&, std::vector<Vec3>& pts) { Collect{pts}(a); }
void collect_exact(const EK::Triangle_3&, const EK::Point_3& b, std::vector<Vec3>& pts) { Collect{pts}(b); }

// The part of triangle `t` on the plane n.x = c, as the two extreme points along `dir`.
// Returns false if the triangle does not reach the plane (rounding can say so for a graze).
bool cut_by_plane(const TriangleCorners& t, const Vec3& n, double c, const Vec3& dir, Vec3& lo, Vec3& hi) {
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = n.dot(t[i]) - c;
  Vec3 pts[6];
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (d[i] == 0.0) pts[count++] = t[i];
    if ((d[i] < 0 && d[j] > 0) || (d[i] > 0 && d[j] < 0)) pts[count++] = t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j]));
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
// plane gives a segment on the common line; the intersection is their overlap.
bool crossing_segment(const TriangleCorners& a, const TriangleCorners& b, Vec3& p, Vec3& q) {
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
  const Vec3 dir = na.cross(nb);
  if (!(dir.squaredNorm() > 0.0)) return false;
  Vec3 alo, ahi, blo, bhi;
  if (!cut_by_plane(a, nb, nb.dot(b[0]), dir, alo, ahi) || !cut_by_plane(b, na, na.dot(a[0]), dir, blo, bhi))
    return false;
  p = alo.dot(dir) > blo.dot(dir) ? alo : blo;  // the later start
  q = ahi.dot(dir) < bhi.dot(dir) ? ahi : bhi;  // the earlier end
  if (p.dot(dir) > q.dot(dir)) p = q = 0.5 * (p + q);  // a touch, split by rounding
  return true;
}

}  // namespace

bool triangles_intersect(const TriangleCorners& a, const TriangleCorners& b) {
  const Simplex sa = simplex(a), sb = simplex(b);
  return std::visit([](const auto& x, const auto& y) { return intersect(x, y); }, sa, sb);
}

std::pair<Vec3, Vec3> intersection_segment(const TriangleCorners& a, const TriangleCorners& b) {
  const Simplex sa = simplex(a), sb = simplex(b);
  // Common case: two proper triangles crossing, not coplanar: constructed in double.
  if (std::holds_alternative<T3>(sa) && std::holds_alternative<T3>(sb)) {
    const T3& ta = std::get<T3>(sa);
    const bool coplanar = CGAL::coplanar(ta[0], ta[1], ta[2], to_cgal(b[0])) &&
                          CGAL::coplanar(ta[0], ta[1], ta[2], to_cgal(b[1])) &&
                          CGAL::coplanar(ta[0], ta[1], ta[2], to_cgal(b[2]));
    Vec3 p, q;
    if (!coplanar && crossing_segment(a, b, p, q)) return {p, q};
  }
  // Coplanar overlaps, degenerate triangles, and grazes that rounding lost: exact constructions.
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

void narrow_phase(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates,
                  std::vector<Contact>& out) {
  for (std::uint64_t c : candidates) {
    const std::uint32_t ta = pair_a(c), tb = pair_b(c);
    const TriangleCorners ca = corners(a, ta), cb = corners(b, tb);
    if (!triangles_intersect(ca, cb)) continue;
    Contact contact;
    contact.tri_a = ta;
    contact.tri_b = tb;
    std::tie(contact.p, contact.q) = intersection_segment(ca, cb);
    out.push_back(contact);
  }
}

}  // namespace peelcd
