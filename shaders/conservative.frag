#version 450 core
// Conservative mode, step 2: keeps the texels the triangle (grown by its margin) really touches,
// by separating axes, and stores the depth interval it spans over the texel in the k-buffer of
// shaders/abuffer.frag: lower depth bits, object << 31 | draw order, upper depth bits, 0.
// The arithmetic and the constants are peelcd/core/image/conservative.h's (texel_interval).
flat in vec3 g_x;
flat in vec3 g_y;
flat in vec3 g_z;
flat in vec2 g_margin;
flat in uint g_order;

#ifdef PEELCD_BATCH  // shaders/conservative.vert
flat in uint g_view;  // view << 1 | object
#include "batch.inc"  // the views
// The packed k-buffer is compact: a count pass (count_only) counts each texel's fragments, the
// host turns the counts into offsets, and the fill pass stores texel t's fragments from
// offsets[t] on: it holds every fragment, with no slot limit and nothing drawn twice to regrow.
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };
uniform bool count_only;
#else
uniform uint object_bit;  // 0 for object A, 1 for object B
uniform int resolution;
#endif
uniform uint slots;

layout(std430, binding = 2) buffer Counts { uint counts[]; };
layout(std430, binding = 1) writeonly buffer Fragments { uvec4 fragments[]; };

const float kWindowRel = 1.0 / 1048576.0;
const float kDepthAbs = 1.0 / 4194304.0;
const float kSliver = 1.0 / 256.0;
const float kPlaneRel = 1.0 / 1024.0;

float min3(vec3 v) { return min(min(v.x, v.y), v.z); }
float max3(vec3 v) { return max(max(v.x, v.y), v.z); }

void main() {
#ifdef PEELCD_BATCH
  int resolution = views[g_view >> 1].info.x;
  uint object_bit = g_view & 1u;
#endif
  ivec2 ij = ivec2(gl_FragCoord.xy);
  if (ij.x < 0 || ij.y < 0 || ij.x >= resolution || ij.y >= resolution) return;
  float h = 0.5 + g_margin.x;
  float cx = float(ij.x) + 0.5, cy = float(ij.y) + 0.5;
  float xmin = min3(g_x), xmax = max3(g_x), ymin = min3(g_y), ymax = max3(g_y);
  if (xmax < cx - h || xmin > cx + h || ymax < cy - h || ymin > cy + h) return;
  float big = max(max(max(abs(xmin), abs(xmax)), max(abs(ymin), abs(ymax))), max(cx, cy));
  for (int k = 0; k < 3; ++k) {
    int k1 = k == 2 ? 0 : k + 1;
    float nx = g_y[k] - g_y[k1], ny = g_x[k1] - g_x[k];
    vec3 p = nx * g_x + ny * g_y;
    float an = abs(nx) + abs(ny);
    float sc = nx * cx + ny * cy, sr = h * an;
    float tol = 4.0 * kWindowRel * an * big;
    if (max3(p) < sc - sr - tol || min3(p) > sc + sr + tol) return;
  }
  float mz = g_margin.y;
  float lo = min3(g_z) - mz, hi = max3(g_z) + mz;
  float e1x = g_x.y - g_x.x, e1y = g_y.y - g_y.x, e1z = g_z.y - g_z.x;
  float e2x = g_x.z - g_x.x, e2y = g_y.z - g_y.x, e2z = g_z.z - g_z.x;
  float det = e1x * e2y - e1y * e2x;
  if (abs(det) > kSliver * (abs(e1x) + abs(e1y)) * (abs(e2x) + abs(e2y))) {
    float a = (e1z * e2y - e2z * e1y) / det, b = (e1x * e2z - e2x * e1z) / det;
    float dx = cx - g_x.x, dy = cy - g_y.x;
    float zc = g_z.x + a * dx + b * dy;
    float r = (abs(a) + abs(b)) * h;
    float w = kPlaneRel * (abs(a) * abs(dx) + abs(b) * abs(dy) + r) + mz + kDepthAbs;
    float plo = zc - r - w, phi = zc + r + w;
    if (!isinf(plo) && !isnan(plo) && !isinf(phi) && !isnan(phi)) {
      lo = max(lo, plo);
      hi = min(hi, phi);
    }
  }
  lo = max(lo, 0.0);
  hi = min(hi, 1.0);
  if (!(lo <= hi)) return;
#ifdef PEELCD_BATCH
  uint texel = uint(views[g_view >> 1].info.y) + uint(ij.y) * uint(resolution) + uint(ij.x);
#else
  uint texels = uint(resolution) * uint(resolution);
  uint texel = uint(ij.y) * uint(resolution) + uint(ij.x);
#endif
  uint s = atomicAdd(counts[texel], 1u);
#ifdef PEELCD_BATCH
  if (count_only) return;
  fragments[offsets[texel] + s] = uvec4(floatBitsToUint(lo), (object_bit << 31) | g_order, floatBitsToUint(hi), 0u);
#else
  if (s >= slots) return;  // the resolve sees the count and asks the host for more slots
  fragments[s * texels + texel] = uvec4(floatBitsToUint(lo), (object_bit << 31) | g_order, floatBitsToUint(hi), 0u);
#endif
}
