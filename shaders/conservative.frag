#version 450 core
// Conservative mode, step 2: keeps the texels the triangle (grown by its margin) really touches,
// by separating axes, and stores the depth interval it spans over the texel in the k-buffer of
// shaders/abuffer.frag: lower depth bits, object << 31 | draw order, upper depth bits, 0.
// The arithmetic is shaders/conservative.inc's (cover_texel()), shared with the compute path.
flat in vec3 g_x;
flat in vec3 g_y;
flat in vec3 g_z;
flat in vec2 g_margin;
flat in uint g_order;

#ifdef PEELCD_BATCH  // shaders/conservative.vert
flat in uint g_view;  // view << 1 | object
#include "batch.inc"  // the views
#else
uniform uint object_bit;  // 0 for object A, 1 for object B
uniform int resolution;
#endif

#define PEELCD_COVER_STORE
#include "conservative.inc"  // cover_texel(), cover_store()

void main() {
#ifdef PEELCD_BATCH
  int resolution = views[g_view >> 1].info.x;
  uint object_bit = g_view & 1u;
#endif
  float lo, hi;
  if (!cover_texel(ivec2(gl_FragCoord.xy), resolution, g_x, g_y, g_z, g_margin, lo, hi)) return;
  ivec2 ij = ivec2(gl_FragCoord.xy);
#ifdef PEELCD_BATCH
  uint texel = uint(views[g_view >> 1].info.y) + uint(ij.y) * uint(resolution) + uint(ij.x);
#else
  uint texel = uint(ij.y) * uint(resolution) + uint(ij.x);
#endif
  cover_store(texel, uint(resolution) * uint(resolution), lo, hi, object_bit, g_order);
}
