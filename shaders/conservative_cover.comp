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
// With PEELCD_COVER_SHARE defined (GlOptions::cover_share_texels), a triangle whose box holds more
// than that many texels does not walk it alone: its window coordinates and margins go
// to the workgroup's shared memory, and the 64 invocations of the group walk the boxes of all
// such triangles of the group together, texel by texel (a large triangle would otherwise keep
// its invocation, and on a GPU its warp, busy for the whole box while the others wait). Every
// texel runs the same cover_texel() on the same values: the same fragments.
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

#ifdef PEELCD_COVER_SHARE
// The group's shared triangles: what cover_texel() and cover_store() need, and where each one's
// texels start in the group's run of them (start[64] is the run's length).
shared vec3 share_x[64], share_y[64], share_z[64];
shared vec2 share_margin[64];
shared ivec4 share_box[64];   // first texel (i, j) of the box, its width, the view's resolution
shared uvec3 share_store[64];  // first texel of the view in the k-buffer, object, order
shared uint share_start[65];
#endif

void main() {
#ifndef PEELCD_BATCH
  uint row = flags.y;
  int resolution = int(sizes.x);
  uint object_bit = sizes.z, triangles = sizes.w;
  bool indexed = flags.x != 0u;
  float grow_texels = uintBitsToFloat(flags.z), grow_depth = uintBitsToFloat(flags.w);
#endif
  uint lane = gl_LocalInvocationIndex;
  uint k = gl_GlobalInvocationID.y * row + gl_GlobalInvocationID.x;
  // No invocation returns before the barriers below (with PEELCD_COVER_SHARE): those past the
  // draw's triangles, or whose triangle no texel can hold, share nothing.
  uint shared_texels = 0u;
  vec3 local[3], mag[3];
#ifdef PEELCD_BATCH
  bool live = k < command[0] / 3u;
  uvec4 e = live ? entries[k] : uvec4(0u);
  uint view = e.y >> 1, object_bit = e.y & 1u;
  int resolution = views[view].info.x;
  float grow_texels = views[view].half_box.w;
  float grow_depth = intBitsToFloat(views[view].info.w);
  uint first_texel = uint(views[view].info.y);
  uint order = k;  // the draw's gl_VertexID / 3
  mat4 clip_from_local = views[view].clip_from_local;
  if (live) {
    mat4 roi_from_object = views[view].roi_from_object[object_bit];
    for (uint c = 0u; c < 3u; ++c) cover_corner(entry_position(e, c), roi_from_object, local[c], mag[c]);
  }
#else
  bool live = k < triangles;
  uint order = live && indexed ? indices[3u * k] / 3u : k;  // the draw's first corner's gl_VertexID / 3
  if (live)
    for (uint c = 0u; c < 3u; ++c) {
      uint v = indexed ? indices[3u * k + c] : 3u * k + c;
      cover_corner(uintBitsToFloat(corners[v].xyz), roi_from_object, local[c], mag[c]);
    }
  uint first_texel = 0u;
#endif
  uint texels = uint(resolution) * uint(resolution);
  if (live) {
    float n = float(resolution);
    vec3 wx, wy, wz;
    vec2 margin, lo, hi;
    if (cover_triangle(local, mag, clip_from_local, n, grow_texels, grow_depth, wx, wy, wz, margin, lo, hi)) {
      // Texel i's centre i + 0.5 inside [lo, hi] (lo and hi within [-1, n + 1]), within the view.
      ivec2 first = max(ivec2(floor(lo - 0.5)), ivec2(0));
      ivec2 last = min(ivec2(ceil(hi - 0.5)), ivec2(resolution - 1));
      uint box = first.x <= last.x && first.y <= last.y ? uint(last.x - first.x + 1) * uint(last.y - first.y + 1) : 0u;
      // Shared: up to 2^24 texels (the group's run then fits 32 bits); a larger box (a view
      // beyond 4096^2) is walked alone.
#ifdef PEELCD_COVER_SHARE
      if (box > PEELCD_COVER_SHARE && box <= 16777216u) {
        share_x[lane] = wx;
        share_y[lane] = wy;
        share_z[lane] = wz;
        share_margin[lane] = margin;
        share_box[lane] = ivec4(first, last.x - first.x + 1, resolution);
        share_store[lane] = uvec3(first_texel, object_bit, order);
        shared_texels = box;
      } else
#endif
      {
        for (int j = first.y; j <= last.y; ++j)
          for (int i = first.x; i <= last.x; ++i) {
            float zlo, zhi;
            if (!cover_texel(ivec2(i, j), resolution, wx, wy, wz, margin, zlo, zhi)) continue;
            cover_store(first_texel + uint(j) * uint(resolution) + uint(i), texels, zlo, zhi, object_bit, order);
          }
      }
    }
  }
#ifdef PEELCD_COVER_SHARE
  // The group's shared boxes one after another: start[t] where triangle t's texels begin.
  share_start[lane + 1u] = shared_texels;
  memoryBarrierShared();
  barrier();
  if (lane == 0u) {
    share_start[0] = 0u;
    for (uint t = 1u; t <= 64u; ++t) share_start[t] += share_start[t - 1u];
  }
  memoryBarrierShared();
  barrier();
  uint run = share_start[64];
  for (uint s = lane; s < run; s += 64u) {
    // The triangle t whose texels hold s: the last with start[t] <= s (it has texels: a
    // triangle without shares the start of the next). Six halvings written out: llvmpipe counts
    // every loop iteration of an invocation against one limit (gl/stage_impl.h,
    // compute_coverage()), so the walk is the only loop that grows with the view.
    uint t = 0u;
    if (share_start[t + 32u] <= s) t += 32u;
    if (share_start[t + 16u] <= s) t += 16u;
    if (share_start[t + 8u] <= s) t += 8u;
    if (share_start[t + 4u] <= s) t += 4u;
    if (share_start[t + 2u] <= s) t += 2u;
    if (share_start[t + 1u] <= s) t += 1u;
    uint at = s - share_start[t];
    ivec4 b = share_box[t];
    uvec3 st = share_store[t];
    ivec2 ij = b.xy + ivec2(int(at % uint(b.z)), int(at / uint(b.z)));
    float zlo, zhi;
    if (!cover_texel(ij, b.w, share_x[t], share_y[t], share_z[t], share_margin[t], zlo, zhi)) continue;
    cover_store(st.x + uint(ij.y) * uint(b.w) + uint(ij.x), uint(b.w) * uint(b.w), zlo, zhi, st.y, st.z);
  }
#endif
}
