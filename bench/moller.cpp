// Moller's triangle/triangle interval test in float, as the float peers run it: as published
// (tri_tri_moller, the peers' default) and in a scaled frame (tri_tri_float, a labelled variant).
#include "peelcd/bench/float_peers.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace peelcd::bench {
namespace {

// --- Moller's test, float ------------------------------------------------------------------

using F3 = std::array<float, 3>;
inline F3 sub(const float* a, const float* b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline F3 cross(const F3& a, const F3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline float dot(const F3& a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// 2D: segments p0p1 and q0q1 meet (closed).
bool segments_meet_2d(const float* p0, const float* p1, const float* q0, const float* q1) {
  const auto orient = [](const float* a, const float* b, const float* c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  };
  const float d1 = orient(q0, q1, p0), d2 = orient(q0, q1, p1), d3 = orient(p0, p1, q0), d4 = orient(p0, p1, q1);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  const auto on = [](const float* a, const float* b, const float* c) {
    return std::min(a[0], b[0]) <= c[0] && c[0] <= std::max(a[0], b[0]) && std::min(a[1], b[1]) <= c[1] &&
           c[1] <= std::max(a[1], b[1]);
  };
  return (d1 == 0 && on(q0, q1, p0)) || (d2 == 0 && on(q0, q1, p1)) || (d3 == 0 && on(p0, p1, q0)) ||
         (d4 == 0 && on(p0, p1, q1));
}

bool point_in_tri_2d(const float* p, const float* a, const float* b, const float* c) {
  const auto orient = [](const float* u, const float* v, const float* w) {
    return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0]);
  };
  const float d0 = orient(a, b, p), d1 = orient(b, c, p), d2 = orient(c, a, p);
  return (d0 >= 0 && d1 >= 0 && d2 >= 0) || (d0 <= 0 && d1 <= 0 && d2 <= 0);
}

bool coplanar_tri_tri(const F3& n, const float* v0, const float* v1, const float* v2, const float* u0, const float* u1,
                      const float* u2) {
  // Project onto the plane of the two largest components of the normal.
  const float a0 = std::abs(n[0]), a1 = std::abs(n[1]), a2 = std::abs(n[2]);
  int i0, i1;
  if (a0 > a1) {
    if (a0 > a2) i0 = 1, i1 = 2;
    else i0 = 0, i1 = 1;
  } else {
    if (a2 > a1) i0 = 0, i1 = 1;
    else i0 = 0, i1 = 2;
  }
  const float v[3][2] = {{v0[i0], v0[i1]}, {v1[i0], v1[i1]}, {v2[i0], v2[i1]}};
  const float u[3][2] = {{u0[i0], u0[i1]}, {u1[i0], u1[i1]}, {u2[i0], u2[i1]}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_meet_2d(v[i], v[(i + 1) % 3], u[j], u[(j + 1) % 3])) return true;
  return point_in_tri_2d(v[0], u[0], u[1], u[2]) || point_in_tri_2d(u[0], v[0], v[1], v[2]);
}

// The interval of one triangle on the line of the two planes (Moller's NEWCOMPUTE_INTERVALS);
// false: the triangles are coplanar.
bool intervals(float vv0, float vv1, float vv2, float d0, float d1, float d2, float d0d1, float d0d2, float& a,
               float& b, float& c, float& x0, float& x1) {
  if (d0d1 > 0.0f) {
    a = vv2, b = (vv0 - vv2) * d2, c = (vv1 - vv2) * d2, x0 = d2 - d0, x1 = d2 - d1;
  } else if (d0d2 > 0.0f) {
    a = vv1, b = (vv0 - vv1) * d1, c = (vv2 - vv1) * d1, x0 = d1 - d0, x1 = d1 - d2;
  } else if (d1 * d2 > 0.0f || d0 != 0.0f) {
    a = vv0, b = (vv1 - vv0) * d0, c = (vv2 - vv0) * d0, x0 = d0 - d1, x1 = d0 - d2;
  } else if (d1 != 0.0f) {
    a = vv1, b = (vv0 - vv1) * d1, c = (vv2 - vv1) * d1, x0 = d1 - d0, x1 = d1 - d2;
  } else if (d2 != 0.0f) {
    a = vv2, b = (vv0 - vv2) * d2, c = (vv1 - vv2) * d2, x0 = d2 - d0, x1 = d2 - d1;
  } else {
    return false;
  }
  return true;
}

// Moller's test past the two plane-side checks: the two triangles' intervals on the line of
// their planes (or the coplanar 2D test), given both normals and the corners' plane distances.
bool moller_intervals(const float* v0, const float* v1, const float* v2, const float* u0, const float* u1,
                      const float* u2, const F3& n1, const F3& n2, float du0, float du1, float du2, float dv0, float dv1,
                      float dv2) {
  const float du0du1 = du0 * du1, du0du2 = du0 * du2;
  const float dv0dv1 = dv0 * dv1, dv0dv2 = dv0 * dv2;
  if (dv0dv1 > 0.0f && dv0dv2 > 0.0f) return false;
  const F3 d = cross(n1, n2);
  int index = 0;
  float max = std::abs(d[0]);
  if (std::abs(d[1]) > max) max = std::abs(d[1]), index = 1;
  if (std::abs(d[2]) > max) index = 2;
  float a, b, c, x0, x1, e, f, g, y0, y1;
  if (!intervals(v0[index], v1[index], v2[index], dv0, dv1, dv2, dv0dv1, dv0dv2, a, b, c, x0, x1))
    return coplanar_tri_tri(n1, v0, v1, v2, u0, u1, u2);
  if (!intervals(u0[index], u1[index], u2[index], du0, du1, du2, du0du1, du0du2, e, f, g, y0, y1))
    return coplanar_tri_tri(n1, v0, v1, v2, u0, u1, u2);
  const float xx = x0 * x1, yy = y0 * y1, xxyy = xx * yy;
  float tmp = a * xxyy;
  float i1a = tmp + b * x1 * yy, i1b = tmp + c * x0 * yy;
  tmp = e * xxyy;
  float i2a = tmp + f * xx * y1, i2b = tmp + g * xx * y0;
  if (i1a > i1b) std::swap(i1a, i1b);
  if (i2a > i2b) std::swap(i2a, i2b);
  return !(i1b < i2a || i2b < i1a);
}

}  // namespace

bool tri_tri_float(const std::array<float, 9>& t_in, const std::array<float, 9>& u_in) {
  // In a frame at t's first corner scaled to the pair's extent: the no-division test multiplies
  // up to five small differences, which underflow for small triangles (and flush to zero where
  // Embree sets FTZ/DAZ), deciding differently from call to call.
  std::array<float, 9> t, u;
  float extent = 0.0f, mag = 0.0f;
  for (std::size_t i = 0; i < 9; ++i) {
    const float o = t_in[i % 3];
    t[i] = t_in[i] - o;
    u[i] = u_in[i] - o;
    const float e = std::abs(t[i]) > std::abs(u[i]) ? std::abs(t[i]) : std::abs(u[i]);
    const float g = std::abs(t_in[i]) > std::abs(u_in[i]) ? std::abs(t_in[i]) : std::abs(u_in[i]);
    extent = e > extent ? e : extent;
    mag = g > mag ? g : mag;
  }
  if (extent == 0.0f) return true;  // all six corners on one point
  const float scale = 1.0f / extent;
  for (int k = 0; k < 9; ++k) t[std::size_t(k)] *= scale, u[std::size_t(k)] *= scale;
  mag *= scale;  // the input's rounding (2^-24 of its magnitude), in these units
  // Moller's snap of plane distances to 0 (his USE_EPSILON_TEST), with an epsilon of the input's
  // float rounding instead of his absolute 1e-6 (on the unnormalized normal of a millimetre
  // triangle that snaps a millimetre): a corner within rounding of the other's plane counts as
  // on it, and coplanar pairs go to the 2D test.
  const float *v0 = &t[0], *v1 = &t[3], *v2 = &t[6], *u0 = &u[0], *u1 = &u[3], *u2 = &u[6];
  const F3 n1 = cross(sub(v1, v0), sub(v2, v0));
  // |d| < 4e-7 mag |n|, squared (no square root).
  const float kEps = 1.6e-13f * mag * mag * (n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
  const float d1 = -dot(n1, v0);
  float du0 = dot(n1, u0) + d1, du1 = dot(n1, u1) + d1, du2 = dot(n1, u2) + d1;
  if (du0 * du0 < kEps) du0 = 0.0f;
  if (du1 * du1 < kEps) du1 = 0.0f;
  if (du2 * du2 < kEps) du2 = 0.0f;
  const float du0du1 = du0 * du1, du0du2 = du0 * du2;
  if (du0du1 > 0.0f && du0du2 > 0.0f) return false;
  const F3 n2 = cross(sub(u1, u0), sub(u2, u0));
  const float d2 = -dot(n2, u0);
  const float kEps2 = 1.6e-13f * mag * mag * (n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]);
  float dv0 = dot(n2, v0) + d2, dv1 = dot(n2, v1) + d2, dv2 = dot(n2, v2) + d2;
  if (dv0 * dv0 < kEps2) dv0 = 0.0f;
  if (dv1 * dv1 < kEps2) dv1 = 0.0f;
  if (dv2 * dv2 < kEps2) dv2 = 0.0f;
  return moller_intervals(v0, v1, v2, u0, u1, u2, n1, n2, du0, du1, du2, dv0, dv1, dv2);
}

bool tri_tri_moller(const std::array<float, 9>& t, const std::array<float, 9>& u) {
  // Moller's NoDivTriTriIsect as published (tritri.c), on the floats as given, with his
  // USE_EPSILON_TEST switch off: a plane distance is 0 only when it is. (On, his absolute
  // EPSILON of 1e-6 on unnormalized plane distances calls every pair of centimetre triangles
  // within a centimetre coplanar: on the crumpled cloth 1.2M false pairs and 3.9x the time.)
  const float *v0 = &t[0], *v1 = &t[3], *v2 = &t[6], *u0 = &u[0], *u1 = &u[3], *u2 = &u[6];
  const F3 n1 = cross(sub(v1, v0), sub(v2, v0));
  const float d1 = -dot(n1, v0);
  const float du0 = dot(n1, u0) + d1, du1 = dot(n1, u1) + d1, du2 = dot(n1, u2) + d1;
  const float du0du1 = du0 * du1, du0du2 = du0 * du2;
  if (du0du1 > 0.0f && du0du2 > 0.0f) return false;
  const F3 n2 = cross(sub(u1, u0), sub(u2, u0));
  const float d2 = -dot(n2, u0);
  const float dv0 = dot(n2, v0) + d2, dv1 = dot(n2, v1) + d2, dv2 = dot(n2, v2) + d2;
  return moller_intervals(v0, v1, v2, u0, u1, u2, n1, n2, du0, du1, du2, dv0, dv1, dv2);
}

const char* to_string(TriangleTest test) { return test == TriangleTest::moller ? "moller" : "scaled"; }

}  // namespace peelcd::bench
