// The certified predicates' exact fallbacks, and the two certified "apart" tests of the public
// header (coplanar_apart, apart_across_an_edge): signs decided in double with error bounds.
#include "certified.h"
#include "exact_kernel.h"

namespace peelcd {
namespace exact_detail {

int exact_orientation_sign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  return int(CGAL::orientation(to_cgal(p), to_cgal(q), to_cgal(r), to_cgal(s)));
}

void exact_plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
  for (int i = 0; i < 3; ++i)
    if (side[i] == 0)
      side[i] = int(CGAL::orientation(to_cgal(plane[0]), to_cgal(plane[1]), to_cgal(plane[2]), to_cgal(t[i])));
}

}  // namespace exact_detail

using namespace exact_detail;

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
constexpr double kEdgePlaneBound = 32.0 * kUnitRoundoff;

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

}  // namespace peelcd
