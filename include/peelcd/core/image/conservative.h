#pragma once
// Conservative coverage and depth intervals of one triangle over the texels of a view: what
// shaders/conservative.geom and shaders/conservative.frag compute per fragment, in the same
// float operations, for the CPU image stage (core/image/cpu_stage.cpp). docs/accuracy.md,
// "Conservative mode", gives the argument and the error bounds.
//
// Window coordinates: x, y in texels (texel (i, j) is the square [i, i+1] x [j, j+1]), z the
// window depth (0 at the near face of the ROI's depth range, 1 at the far face).
#include <algorithm>
#include <cmath>
#include <limits>

namespace peelcd::conservative {

// Relative and absolute slack of the bounds below, shared with the shaders.
constexpr float kVertexRel = 1.0f / 131072.0f;   // 2^-17: vertex stage error per unit of |M| |p|
constexpr float kWindowRel = 1.0f / 1048576.0f;  // 2^-20: per texel of window coordinate
constexpr float kTexelAbs = 1.0f / 4096.0f;      // 2^-12 texel
constexpr float kDepthAbs = 1.0f / 4194304.0f;   // 2^-22 of the depth range
constexpr float kSliver = 1.0f / 256.0f;         // |det| below this times |e1| |e2|: whole range
constexpr float kPlaneRel = 1.0f / 1024.0f;      // plane evaluation error bound, relative

struct Triangle {
  float x[3], y[3], z[3];  // window coordinates of the corners
  float mx = 0, mz = 0;    // error margins: texels (x, y), window depth (z)
};

// The margins of a triangle whose corners' clip coordinates carry at most `ex`, `ey`, `ez`
// times kVertexRel of error (|M| |p| + |M_t| per corner, the largest), in a view of n texels;
// plus `gx` texels and `gz` of window depth, the growth for proximity (grow_of()).
inline void set_margins(Triangle& t, float ex, float ey, float ez, int n, float gx = 0.0f, float gz = 0.0f) {
  float big = 0.0f;
  for (int k = 0; k < 3; ++k) big = std::max(big, std::max(std::fabs(t.x[k]), std::fabs(t.y[k])));
  t.mx = std::max(ex, ey) * kVertexRel * (0.5f * float(n)) + kWindowRel * (big + float(n)) + kTexelAbs + gx;
  t.mz = ez * kVertexRel * 0.5f + kDepthAbs + gz;
}

// A growth of `grow` world units (PeelJob::grow) in texels of side `texel` (gx) and in window
// depth over a depth range of `depth_range` world units (gz), rounded up to floats: zero for no
// growth (the margins then are those without proximity, bit for bit).
inline void grow_of(double grow, double texel, double depth_range, float& gx, float& gz) {
  const float inf = std::numeric_limits<float>::infinity();
  gx = grow > 0.0 ? std::nextafter(float(grow / texel), inf) : 0.0f;
  gz = grow > 0.0 ? std::nextafter(float(grow / depth_range), inf) : 0.0f;
}

// Does the triangle, grown by its margins, touch texel (i, j)? If so, [lo, hi] is the depth
// interval it spans over the texel (clamped to [0, 1], the ROI's depth range); false also when
// that interval is empty.
inline bool texel_interval(const Triangle& t, int i, int j, float& lo, float& hi) {
  const float h = 0.5f + t.mx;
  const float cx = float(i) + 0.5f, cy = float(j) + 0.5f;
  // Separating axes: x, y, then the three edges' normals (exact for a triangle, a segment or a
  // point against a square).
  const float xmin = std::min({t.x[0], t.x[1], t.x[2]}), xmax = std::max({t.x[0], t.x[1], t.x[2]});
  const float ymin = std::min({t.y[0], t.y[1], t.y[2]}), ymax = std::max({t.y[0], t.y[1], t.y[2]});
  if (xmax < cx - h || xmin > cx + h || ymax < cy - h || ymin > cy + h) return false;
  const float big = std::max({std::fabs(xmin), std::fabs(xmax), std::fabs(ymin), std::fabs(ymax), cx, cy});
  for (int k = 0; k < 3; ++k) {
    const int k1 = k == 2 ? 0 : k + 1;
    const float nx = t.y[k] - t.y[k1], ny = t.x[k1] - t.x[k];
    const float p0 = nx * t.x[0] + ny * t.y[0], p1 = nx * t.x[1] + ny * t.y[1], p2 = nx * t.x[2] + ny * t.y[2];
    const float tmin = std::min({p0, p1, p2}), tmax = std::max({p0, p1, p2});
    const float an = std::fabs(nx) + std::fabs(ny);
    const float sc = nx * cx + ny * cy, sr = h * an;
    const float tol = 4.0f * kWindowRel * an * big;
    if (tmax < sc - sr - tol || tmin > sc + sr + tol) return false;
  }
  // Depth: the plane's range over the grown texel, clamped to the triangle's own range; a sliver
  // or an edge-on triangle gets its whole range.
  const float zmin = std::min({t.z[0], t.z[1], t.z[2]}) - t.mz, zmax = std::max({t.z[0], t.z[1], t.z[2]}) + t.mz;
  lo = zmin;
  hi = zmax;
  const float e1x = t.x[1] - t.x[0], e1y = t.y[1] - t.y[0], e1z = t.z[1] - t.z[0];
  const float e2x = t.x[2] - t.x[0], e2y = t.y[2] - t.y[0], e2z = t.z[2] - t.z[0];
  const float det = e1x * e2y - e1y * e2x;
  if (std::fabs(det) > kSliver * (std::fabs(e1x) + std::fabs(e1y)) * (std::fabs(e2x) + std::fabs(e2y))) {
    const float a = (e1z * e2y - e2z * e1y) / det, b = (e1x * e2z - e2x * e1z) / det;
    const float dx = cx - t.x[0], dy = cy - t.y[0];
    const float zc = t.z[0] + a * dx + b * dy;
    const float r = (std::fabs(a) + std::fabs(b)) * h;
    const float w = kPlaneRel * (std::fabs(a) * std::fabs(dx) + std::fabs(b) * std::fabs(dy) + r) + t.mz + kDepthAbs;
    const float plo = zc - r - w, phi = zc + r + w;
    if (std::isfinite(plo) && std::isfinite(phi)) {  // else the whole range stands
      lo = std::max(lo, plo);
      hi = std::min(hi, phi);
    }
  }
  lo = std::max(lo, 0.0f);
  hi = std::min(hi, 1.0f);
  return lo <= hi;
}

}  // namespace peelcd::conservative
