#version 450 core
// Conservative mode, step 3: per texel, every two fragments of different objects whose depth
// intervals overlap are a PCS (not only adjacent layers); every fragment is a layer, in
// (lower depth, object, draw order) order. The same set as core/image/kbuffer.cpp's host resolve.
#include "peelcd/core/image/pcs_test.inc"  // pcs_within_epsilon, pcs_intervals_overlap (shared with C++)

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 2, rgba32ui) uniform writeonly uimage2D layer_out;  // capture: layer `emit_layer`
layout(binding = 0) uniform usamplerBuffer count_tex;
layout(binding = 1) uniform usamplerBuffer fragment_tex;  // shaders/conservative.frag
layout(binding = 2) uniform usamplerBuffer corners_a;     // as in shaders/abuffer_resolve.comp
layout(binding = 3) uniform usamplerBuffer corners_b;
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint max_layers;
  uint max_fragments;
  uvec2 pairs[];
};

uniform int resolution;
uniform uint slots;
uniform bool append_pcs;
uniform int emit_layer;  // -1: none

uint id_of(uvec4 f) {
  uint corner = 3u * (f.y & 0x7fffffffu) + 2u;
  return (f.y >> 31) == 0u ? texelFetch(corners_a, int(corner)).w : texelFetch(corners_b, int(corner)).w;
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= resolution || p.y >= resolution) return;
  uint texels = uint(resolution) * uint(resolution);
  uint texel = uint(p.y) * uint(resolution) + uint(p.x);
  uint n = texelFetch(count_tex, int(texel)).x;
  // Some fragments not stored (n > slots: the host grows the k-buffer and draws again), or a
  // texel deeper than one invocation resolves (the host resolves the view): no PCS from here.
  if (n > slots || n > uint(PEELCD_GPU_RESOLVE_DEPTH)) {
    atomicMax(max_fragments, n);
    return;
  }
  uint end = n * texels + texel;
  for (uint i = texel; i < end; i += texels) {
    uvec4 f = texelFetch(fragment_tex, int(i));
    float lo = uintBitsToFloat(f.x), hi = uintBitsToFloat(f.z);
    if (emit_layer >= 0) {
      uint rank = 0u;
      for (uint j = texel; j < end; j += texels) {
        uvec4 g = texelFetch(fragment_tex, int(j));
        float glo = uintBitsToFloat(g.x);
        if (glo < lo || (glo == lo && g.y < f.y)) ++rank;
      }
      if (rank == uint(emit_layer)) imageStore(layer_out, p, uvec4(f.x, (f.y & 0x80000000u) | (id_of(f) + 1u), f.z, 0u));
    }
    if (!append_pcs || (f.y >> 31) != 0u) continue;
    for (uint j = texel; j < end; j += texels) {
      uvec4 g = texelFetch(fragment_tex, int(j));
      if ((g.y >> 31) != 1u) continue;
      if (!pcs_intervals_overlap(lo, hi, uintBitsToFloat(g.x), uintBitsToFloat(g.z))) continue;
      uint slot = atomicAdd(count, 1u);
      if (slot < capacity) pairs[slot] = uvec2(id_of(f), id_of(g));
    }
  }
  if (n > max_layers) atomicMax(max_layers, n);
}
