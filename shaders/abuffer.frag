#version 450 core
// Single-pass peeling, step 1: both objects drawn once; every fragment is stored in one of its
// texel's slots (a k-buffer: a per-texel counter claims the slot atomically; slot s of texel t
// lives at s * texels + t, so neighbouring texels' fragments are neighbours in memory).
// shaders/abuffer_resolve.comp recovers the layers from the slots.
// A fragment is one uvec4: what a peel pass would store for it (shaders/peel.frag) with the
// triangle's place in the draw order in place of its ID (the resolve reads the ID from the
// triangle's provoking corner); the order breaks depth ties the way the depth test does:
//   depth bits, object << 31 | draw order, dz/dx bits, dz/dy bits.
// PEELCD_BATCH (shaders/peel.vert): every point-sampled view of a frame in one packed, compact
// k-buffer, as shaders/conservative.frag's batch: a count pass, then the fill pass stores texel
// t's fragments from offsets[t] on (no slot limit).
flat in uint v_order;  // the triangle's place in the draw order (shaders/peel.vert)
#ifdef PEELCD_BATCH
flat in uint v_view;  // view << 1 | object
#include "batch.inc"  // the views
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };
uniform bool count_only;
#else
uniform uint object_bit;  // 0 for object A, 1 for object B
uniform int resolution;
uniform uint slots;       // fragments a texel can hold; more are counted, not stored
#endif

layout(std430, binding = 2) buffer Counts { uint counts[]; };     // per texel, zeroed per view
layout(std430, binding = 1) writeonly buffer Fragments { uvec4 fragments[]; };

void main() {
  float z = gl_FragCoord.z;
  float gx = dFdx(z), gy = dFdy(z);
  // A peel pass clears depth to 1.0 and tests GL_LESS: a fragment at the far plane never lands.
  if (!(z < 1.0)) return;
#ifdef PEELCD_BATCH
  int resolution = views[v_view >> 1].info.x;
  uint object_bit = v_view & 1u;
  ivec2 ij = ivec2(gl_FragCoord.xy);
  if (ij.x >= resolution || ij.y >= resolution) return;  // the viewport is the largest view's
  uint texel = uint(views[v_view >> 1].info.y) + uint(ij.y) * uint(resolution) + uint(ij.x);
  uint s = atomicAdd(counts[texel], 1u);
  if (count_only) return;
  fragments[offsets[texel] + s] =
      uvec4(floatBitsToUint(z), (object_bit << 31) | v_order, floatBitsToUint(gx), floatBitsToUint(gy));
#else
  uint texels = uint(resolution) * uint(resolution);
  uint texel = uint(gl_FragCoord.y) * uint(resolution) + uint(gl_FragCoord.x);
  uint s = atomicAdd(counts[texel], 1u);
  if (s >= slots) return;  // the resolve sees the count and asks the host for more slots
  fragments[s * texels + texel] =
      uvec4(floatBitsToUint(z), (object_bit << 31) | v_order, floatBitsToUint(gx), floatBitsToUint(gy));
#endif
}
