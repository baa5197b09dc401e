#version 450 core
// Conservative mode, batched (gl/batch.cpp): the packed, compact k-buffer of every ROI view of a
// frame (texel t's fragments from offsets[t] on) resolved in one dispatch, one invocation per
// texel of the whole buffer. As
// shaders/conservative_resolve.comp: every two fragments of different objects whose depth
// intervals overlap are a PCS; here the pair is written as the two triangles' IDs and their view
// (read from the draw's entries: only this list comes back), and each view's deepest texel is
// kept per view.
#include "peelcd/core/pcs_test.inc"  // pcs_intervals_overlap (shared with C++)

layout(local_size_x = 64) in;

layout(binding = 0) uniform usamplerBuffer count_tex;
layout(binding = 1) uniform usamplerBuffer fragment_tex;  // shaders/conservative.frag (PEELCD_BATCH)
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint max_layers;
  uint max_fragments;
  uvec4 pairs[];  // ID of A's triangle, ID of B's, view, 0
};
// first corner, view << 1 | object, the provoking corner's ID, 0 (shaders/conservative.vert)
layout(std430, binding = 4) readonly buffer Entries { uvec4 entries[]; };
layout(std430, binding = 5) buffer ViewLayers { uint view_layers[]; };
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };  // texel t's first fragment

uniform uint texels;  // of the packed k-buffer

void main() {
  uint texel = gl_GlobalInvocationID.x;
  if (texel >= texels) return;
  uint n = texelFetch(count_tex, int(texel)).x;
  if (n == 0u) return;
  uint begin = offsets[texel], end = begin + n;
  uint first = texelFetch(fragment_tex, int(begin)).y & 0x7fffffffu;
  atomicMax(view_layers[entries[first].y >> 1], n);
  if (n > max_layers) atomicMax(max_layers, n);
  for (uint i = begin; i < end; ++i) {
    uvec4 f = texelFetch(fragment_tex, int(i));
    if ((f.y >> 31) != 0u) continue;
    float lo = uintBitsToFloat(f.x), hi = uintBitsToFloat(f.z);
    for (uint j = begin; j < end; ++j) {
      uvec4 g = texelFetch(fragment_tex, int(j));
      if ((g.y >> 31) != 1u) continue;
      if (!pcs_intervals_overlap(lo, hi, uintBitsToFloat(g.x), uintBitsToFloat(g.z))) continue;
      uint slot = atomicAdd(count, 1u);
      if (slot < capacity) {
        uvec4 ea = entries[f.y & 0x7fffffffu], eb = entries[g.y & 0x7fffffffu];
        pairs[slot] = uvec4(ea.z, eb.z, ea.y >> 1, 0u);
      }
    }
  }
}
