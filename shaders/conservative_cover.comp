#version 450 core
// Conservative coverage by compute (GlOptions::coverage compute): what shaders/conservative.vert,
// .geom and .frag do through the rasterizer, one invocation per triangle. The invocation runs
// the vertex and geometry steps on its three corners (shaders/conservative.inc: cover_corner(),
// cover_triangle()), then the fragment step (cover_texel(), cover_store()) on every texel whose
// centre lies inside the box the geometry step would have drawn as a quad: a superset of the
// texels the fragment step keeps (the box is that test's, grown by 1/16 texel), so the same
// fragments are stored with the same bits, only in another order within a texel (which the
// resolves sort away, as they do the rasterizer's). The rasterizer's fixed-function work (clip,
// setup, coverage) is replaced by a loop over the box: for a device whose raster engine is the
// bottleneck (docs/backends.md, "Raster or compute for coverage").
// PEELCD_BATCH: the draw's entries (shaders/batch.inc), the triangle count from the indirect
// draw's command (the selection passes append to it). Otherwise: one object of a one-view draw,
// its corners (x, y, z float bits, ID) and, for a rigid shape, the selected triangles' indices.
layout(local_size_x = 64) in;

#ifdef PEELCD_BATCH
#define PEELCD_BATCH_ENTRIES
#include "batch.inc"  // the views, the entries, entry_position()
layout(std430, binding = 10) readonly buffer Command { uint command[4]; };
#else
layout(std430, binding = 18) readonly buffer Corners { uvec4 corners[]; };
layout(std430, binding = 19) readonly buffer Indices { uint indices[]; };
// The dispatch's parameters, in a buffer rather than uniforms (zink over lavapipe, Mesa 22.3,
// kept a compute program's earlier uniform values after they changed between dispatches).
layout(std430, binding = 20) readonly buffer Params {
  mat4 roi_from_object;
  mat4 clip_from_local;
  uvec4 sizes;  // resolution, slots, object (0: A, 1: B), triangles of the draw
  uvec4 flags;  // indexed (a rigid shape's corners through its selected triangles' indices),
                // invocations a row, the growth in texels and in window depth (float bits)
};
#define PEELCD_COVER_SLOTS sizes.y
#endif
#ifdef PEELCD_BATCH
uniform uint row;  // invocations a row of the dispatch (the x groups times 64)
#endif

#define PEELCD_COVER_STORE
#include "conservative.inc"

void main() {
#ifndef PEELCD_BATCH
  uint row = flags.y;
  int resolution = int(sizes.x);
  uint object_bit = sizes.z, triangles = sizes.w;
  bool indexed = flags.x != 0u;
  float grow_texels = uintBitsToFloat(flags.z), grow_depth = uintBitsToFloat(flags.w);
#endif
  uint k = gl_GlobalInvocationID.y * row + gl_GlobalInvocationID.x;
  vec3 local[3], mag[3];
#ifdef PEELCD_BATCH
  if (k >= command[0] / 3u) return;
  uvec4 e = entries[k];
  uint view = e.y >> 1, object_bit = e.y & 1u;
  mat4 roi_from_object = views[view].roi_from_object[object_bit];
  for (uint c = 0u; c < 3u; ++c) cover_corner(entry_position(e, c), roi_from_object, local[c], mag[c]);
  mat4 clip_from_local = views[view].clip_from_local;
  int resolution = views[view].info.x;
  float grow_texels = views[view].half_box.w;
  float grow_depth = intBitsToFloat(views[view].info.w);
  uint first_texel = uint(views[view].info.y);
  uint order = k;  // the draw's gl_VertexID / 3
#else
  if (k >= triangles) return;
  uint order = indexed ? indices[3u * k] / 3u : k;  // the draw's first corner's gl_VertexID / 3
  for (uint c = 0u; c < 3u; ++c) {
    uint v = indexed ? indices[3u * k + c] : 3u * k + c;
    cover_corner(uintBitsToFloat(corners[v].xyz), roi_from_object, local[c], mag[c]);
  }
  uint first_texel = 0u;
#endif
  float n = float(resolution);
  vec3 wx, wy, wz;
  vec2 margin, lo, hi;
  if (!cover_triangle(local, mag, clip_from_local, n, grow_texels, grow_depth, wx, wy, wz, margin, lo, hi)) return;
  // Texel i's centre i + 0.5 inside [lo, hi] (lo and hi within [-1, n + 1]), within the view.
  ivec2 first = max(ivec2(floor(lo - 0.5)), ivec2(0));
  ivec2 last = min(ivec2(ceil(hi - 0.5)), ivec2(resolution - 1));
  uint texels = uint(resolution) * uint(resolution);
  for (int j = first.y; j <= last.y; ++j)
    for (int i = first.x; i <= last.x; ++i) {
      float zlo, zhi;
      if (!cover_texel(ivec2(i, j), resolution, wx, wy, wz, margin, zlo, zhi)) continue;
      cover_store(first_texel + uint(j) * uint(resolution) + uint(i), texels, zlo, zhi, object_bit, order);
    }
}
