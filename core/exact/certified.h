#pragma once
// Private to the exact narrow phase (narrow_phase.cpp, certified.cpp, constructions.cpp): the
// orientation predicates evaluated in double with a certified error bound (Shewchuk's), which
// decide most signs without exact arithmetic, and their exact fallbacks. Inline: the triangle
// test runs them on every candidate.
#include "peelcd/core/exact/bvh.h"  // PEELCD_ALWAYS_INLINE
#include "peelcd/core/exact/narrow_phase.h"

#include <cmath>

namespace peelcd::exact_detail {

// The unit roundoff of double, 2^-53: a rounded operation's relative error is at most this.
constexpr double kUnitRoundoff = 0x1p-53;

// Shewchuk's orient3d error bound (Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates, 1997): with eps = 2^-53, |det - exact| <= (7 + 56 eps) eps * permanent
// when nothing overflows or underflows. The absolute term covers underflow; an overflow gives
// inf or NaN, which no comparison below accepts.
constexpr double kOrient3dBound = (7.0 + 56.0 * kUnitRoundoff) * kUnitRoundoff;
// Any bound gets this much added: a product that underflowed lost at most this (an exact
// determinant that small is left to the exact predicates).
constexpr double kUnderflowSlack = 1e-290;

// The sign of orient3d(p, q, r, d) when the double evaluation certifies it: +1, -1, or 0 when it
// cannot (then the exact predicates decide).
inline int certain_orientation(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& d) {
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

// The axis (0, 1, 2) whose coordinate is the same double in the three corners of `a` (and of
// `b` when given: both triangles in one axis-aligned plane, exactly), or -1.
inline int axis_plane(const TriangleCorners& a, const TriangleCorners* b = nullptr) {
  for (int k = 0; k < 3; ++k) {
    const double c = a[0][k];
    if (a[1][k] == c && a[2][k] == c && (!b || ((*b)[0][k] == c && (*b)[1][k] == c && (*b)[2][k] == c))) return k;
  }
  return -1;
}

// Shewchuk's orient2d bound: |det - exact| <= (3 + 16 eps) eps (|left| + |right|), eps = 2^-53.
constexpr double kOrient2dBound = (3.0 + 16.0 * kUnitRoundoff) * kUnitRoundoff;

// The sign of orient2d(p, q, r) in the coordinates (u, v) when the double evaluation certifies
// it, else 0 (too close to call, or a product under- or overflowing).
inline int certain_orientation_2d(const Vec3& p, const Vec3& q, const Vec3& r, int u, int v) {
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
PEELCD_ALWAYS_INLINE bool certain_plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
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

inline bool all_zero(const int s[3]) { return s[0] == 0 && s[1] == 0 && s[2] == 0; }
inline bool one_open_side(const int s[3]) { return s[0] != 0 && s[0] == s[1] && s[1] == s[2]; }

// CGAL's orientation(p, q, r, s) as -1, 0, +1, exactly (slow; orientation_sign() first).
int exact_orientation_sign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s);
// CGAL's orientation(p, q, r, s) as -1, 0, +1 (positive: s on the positive side of the oriented
// plane pqr): certified in double where the bound allows (Shewchuk's det has the opposite sign),
// CGAL's exact predicate otherwise. Inline: every couple that crosses both planes runs it twice.
inline int orientation_sign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const int certain = certain_orientation(p, q, r, s);
  if (__builtin_expect(certain != 0, 1)) return -certain;
  return exact_orientation_sign(p, q, r, s);
}
// The sides certain_plane_sides() left at 0, decided by CGAL (exact; rare, and slow).
void exact_plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]);
// Every side of `t`'s corners against `plane`'s plane: certified, else exact.
inline void plane_sides(const TriangleCorners& plane, const TriangleCorners& t, int side[3]) {
  if (!certain_plane_sides(plane, t, side)) exact_plane_sides(plane, t, side);
}

}  // namespace peelcd::exact_detail
