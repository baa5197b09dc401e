#include "core/narrow_phase.h"

#include "core/id_map.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <variant>

namespace peelcd {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using S3 = K::Segment_3;
using T3 = K::Triangle_3;

P3 to_cgal(const Vec3& p) { return P3(p.x(), p.y(), p.z()); }
Vec3 to_eigen(const P3& p) { return Vec3(p.x(), p.y(), p.z()); }

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

// Appends every point of a CGAL intersection result to `pts`.
struct Collect {
  std::vector<Vec3>& pts;
  void operator()(const P3& p) const { pts.push_back(to_eigen(p)); }
  void operator()(const S3& s) const {
    pts.push_back(to_eigen(s.source()));
    pts.push_back(to_eigen(s.target()));
  }
  void operator()(const T3& t) const {
    for (int i = 0; i < 3; ++i) pts.push_back(to_eigen(t.vertex(i)));
  }
  void operator()(const std::vector<P3>& poly) const {
    for (const P3& p : poly) pts.push_back(to_eigen(p));
  }
};

template <class A, class B>
void collect(const A& a, const B& b, std::vector<Vec3>& pts) {
  if (auto r = CGAL::intersection(a, b)) boost::apply_visitor(Collect{pts}, *r);
}
void collect(const P3& a, const P3&, std::vector<Vec3>& pts) { pts.push_back(to_eigen(a)); }
void collect(const P3& a, const S3&, std::vector<Vec3>& pts) { pts.push_back(to_eigen(a)); }
void collect(const S3&, const P3& b, std::vector<Vec3>& pts) { pts.push_back(to_eigen(b)); }
void collect(const P3& a, const T3&, std::vector<Vec3>& pts) { pts.push_back(to_eigen(a)); }
void collect(const T3&, const P3& b, std::vector<Vec3>& pts) { pts.push_back(to_eigen(b)); }

}  // namespace

bool triangles_intersect(const TriangleCorners& a, const TriangleCorners& b) {
  const Simplex sa = simplex(a), sb = simplex(b);
  return std::visit([](const auto& x, const auto& y) { return intersect(x, y); }, sa, sb);
}

std::pair<Vec3, Vec3> intersection_segment(const TriangleCorners& a, const TriangleCorners& b) {
  const Simplex sa = simplex(a), sb = simplex(b);
  std::vector<Vec3> pts;
  std::visit([&](const auto& x, const auto& y) { collect(x, y, pts); }, sa, sb);
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
