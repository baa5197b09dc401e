#version 450 core
// Conservative mode, batched (gl/batch.cpp): the packed, compact k-buffer of every ROI view of a
// frame (texel t's fragments from offsets[t] on) resolved in one dispatch, one invocation per
// texel of the whole buffer. As
// shaders/conservative_resolve.comp: every two fragments of different objects whose depth
// intervals overlap are a PCS; here the pair is written as the two triangles' IDs and their view
// (read from the draw's entries: only this list comes back), and each view's deepest texel is
// kept per view.
// A texel with more than PEELCD_GPU_RESOLVE_DEPTH (D) fragments is not resolved by its own
// invocation: it appends one row per block of D fragments to the deep rows, and the second
// program (this source with PEELCD_DEEP) resolves them, one work group of D invocations per
// (row, block of D fragments): invocation i of row r tests fragment D * r.block + i against the
// block's D fragments. No invocation loops more than D * D times in the first pass (its own
// texel's couples, or its rows) or D times in the second, whatever a texel's depth.
// With PEELCD_FILTER_APART (GlOptions::gpu_filter; a program of its own), a couple whose two
// triangles are certainly apart (peelcd/core/image/certified_apart.inc: a separating axis that no
// rounding can close, by more than the proximity margin) is not written, only counted: only
// couples that may touch come back to the host.
#include "peelcd/core/image/pcs_test.inc"  // pcs_intervals_overlap (shared with C++)
#include "peelcd/core/image/certified_apart.inc"
#define PEELCD_BATCH_CORNERS  // entry_position(): the draw's corners, as the draw bound them
#include "batch.inc"  // the views' records (their poses and growth)

#ifdef PEELCD_DEEP
layout(local_size_x = PEELCD_GPU_RESOLVE_DEPTH) in;
#else
layout(local_size_x = 64) in;
#endif

layout(binding = 0) uniform usamplerBuffer count_tex;
layout(binding = 1) uniform usamplerBuffer fragment_tex;  // shaders/conservative.frag (PEELCD_BATCH)
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint max_layers;
  uint max_fragments;  // the most fragments of a texel too deep for the deep rows (> 65535 blocks)
  uint couples_apart;  // couples the certified filter dropped (PEELCD_FILTER_APART)
  uint pad0, pad1, pad2;
  uvec4 pairs[];       // ID of A's triangle, ID of B's, view, 0
};
// first corner, view << 1 | object, the provoking corner's ID, 0 (shaders/conservative.vert)
layout(std430, binding = 4) readonly buffer Entries { uvec4 entries[]; };
layout(std430, binding = 5) buffer ViewLayers { uint view_layers[]; };
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };  // texel t's first fragment
// The deep texels' rows: (texel, block of D fragments); row_count may exceed row_capacity (then
// none past it is written: the host grows the buffer and resolves again); max_blocks: the most
// blocks of a deep texel (the second dispatch's height).
layout(std430, binding = 15) buffer DeepRows {
  uint row_count;
  uint row_capacity;
  uint max_blocks;
  uint deep_texels;
  uvec2 rows[];
};


uniform uint texels;    // of the packed k-buffer
uniform uint row_base;  // PEELCD_DEEP: the first row of this dispatch

// Corner k of entry e in ROI-local coordinates, as shaders/conservative.vert places it, and its
// error bound (the largest coordinate of |M| |x| + |t| made certified_corner_error()).
vec3 entry_corner(uvec4 e, uint k, out float error) {
  vec3 x = entry_position(e, k);  // the draw's corner (shaders/batch.inc)
  mat4 m = views[e.y >> 1].roi_from_object[e.y & 1u];
  vec3 magnitude = mat3(abs(m[0].xyz), abs(m[1].xyz), abs(m[2].xyz)) * abs(x) + abs(m[3].xyz);
  error = certified_corner_error(max(max(magnitude.x, magnitude.y), magnitude.z));
  return (m * vec4(x, 1.0)).xyz;
}

// Whether the couple's triangles are certainly farther apart than the view's margin (twice its
// growth, box_lo.w).
bool certainly_apart(uvec4 ea, uvec4 eb) {
  float e0, e1, e2, e3, e4, e5;
  vec3 p0 = entry_corner(ea, 0u, e0), p1 = entry_corner(ea, 1u, e1), p2 = entry_corner(ea, 2u, e2);
  vec3 q0 = entry_corner(eb, 0u, e3), q1 = entry_corner(eb, 1u, e4), q2 = entry_corner(eb, 2u, e5);
  float reach = 2.0 * views[ea.y >> 1].box_lo.w;
  return certified_apart(p0, p1, p2, max(max(e0, e1), e2), q0, q1, q2, max(max(e3, e4), e5), reach);
}

uint apart_here = 0u;  // this invocation's couples dropped by the filter, added once at its end

// Fragments i and j of one texel (A's and B's): a PCS if their intervals overlap (and, filtered,
// their triangles may touch).
void test_couple(uvec4 f, uvec4 g) {
  if (!pcs_intervals_overlap(uintBitsToFloat(f.x), uintBitsToFloat(f.z), uintBitsToFloat(g.x), uintBitsToFloat(g.z)))
    return;
  uvec4 ea = entries[f.y & 0x7fffffffu], eb = entries[g.y & 0x7fffffffu];
#ifdef PEELCD_FILTER_APART
  if (certainly_apart(ea, eb)) {
    ++apart_here;
    return;
  }
#endif
  uint slot = atomicAdd(count, 1u);
  if (slot < capacity) pairs[slot] = uvec4(ea.z, eb.z, ea.y >> 1, 0u);
}

#ifdef PEELCD_DEEP
void main() {
  const uint D = uint(PEELCD_GPU_RESOLVE_DEPTH);
  uint r = row_base + gl_WorkGroupID.x;
  if (r >= min(row_count, row_capacity)) return;
  uvec2 row = rows[r];
  uint n = texelFetch(count_tex, int(row.x)).x;
  uint i = row.y * D + gl_LocalInvocationID.x, j0 = gl_WorkGroupID.y * D;
  if (i >= n || j0 >= n) return;
  uint begin = offsets[row.x];
  uvec4 f = texelFetch(fragment_tex, int(begin + i));
  if ((f.y >> 31) != 0u) return;
  uint j1 = min(n, j0 + D);
  for (uint j = j0; j < j1; ++j) {
    uvec4 g = texelFetch(fragment_tex, int(begin + j));
    if ((g.y >> 31) == 1u) test_couple(f, g);
  }
  if (apart_here > 0u) atomicAdd(couples_apart, apart_here);
}
#else
void main() {
  uint texel = gl_GlobalInvocationID.x;
  if (texel >= texels) return;
  uint n = texelFetch(count_tex, int(texel)).x;
  if (n == 0u) return;
  uint begin = offsets[texel], end = begin + n;
  uint first = texelFetch(fragment_tex, int(begin)).y & 0x7fffffffu;
  atomicMax(view_layers[entries[first].y >> 1], n);
  if (n > max_layers) atomicMax(max_layers, n);
  const uint D = uint(PEELCD_GPU_RESOLVE_DEPTH);
  if (n > D) {  // a deep texel: its rows for the second program
    uint blocks = (n + D - 1u) / D;
    if (blocks > 16384u) {  // more rows than one invocation writes: the host resolves the batch
      atomicMax(max_fragments, n);
      return;
    }
    atomicAdd(deep_texels, 1u);
    atomicMax(max_blocks, blocks);
    uint at = atomicAdd(row_count, blocks);
    if (at + blocks <= row_capacity)
      for (uint b = 0u; b < blocks; ++b) rows[at + b] = uvec2(texel, b);
    return;
  }
  for (uint i = begin; i < end; ++i) {
    uvec4 f = texelFetch(fragment_tex, int(i));
    if ((f.y >> 31) != 0u) continue;
    for (uint j = begin; j < end; ++j) {
      uvec4 g = texelFetch(fragment_tex, int(j));
      if ((g.y >> 31) == 1u) test_couple(f, g);
    }
  }
  if (apart_here > 0u) atomicAdd(couples_apart, apart_here);
}
#endif
