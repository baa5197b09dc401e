#version 450 core
// Single-pass peeling, step 2: per texel, the layers of design.md recovered from the fragments
// stored by shaders/abuffer.frag, exactly as the multi-pass peel (shaders/peel.frag) builds
// them: layer 0 is the nearest fragment of the first object (alternate) or of both (full);
// layer k+1 the nearest fragment of the next object (alternate) or of either (full) behind
// layer k in (depth, rank) order (rank = object ^ first object in alternate peeling, the object
// in full peeling: a fragment of the other object at the same depth is behind it); the texel
// ends at the first layer with no such fragment. Depth ties between candidates go to the lower
// rank, then the earlier-drawn triangle, as GL_LESS does with object A drawn first.
// The PCS test between adjacent layers is shaders/pcs.comp's, run start included.
// PEELCD_BATCH (gl/batch.cpp): the packed, compact k-buffer of every point-sampled view of a
// frame (texel t's fragments from offsets[t] on) in one dispatch, one invocation per texel; a
// texel's view (its threshold, slope, peel mode) is its first fragment's entry's; a PCS is
// written as the two triangles' IDs and the view (only this list comes back), and each view's
// deepest texel is kept per view. No layer capture (views capturing layers are peeled alone).
#include "peelcd/core/image/pcs_test.inc"  // pcs_within_epsilon, pcs_intervals_overlap (shared with C++)

#ifdef PEELCD_BATCH
layout(local_size_x = 64) in;
#include "batch.inc"  // the views
layout(binding = 0) uniform usamplerBuffer count_tex;
layout(binding = 1) uniform usamplerBuffer fragment_tex;  // shaders/abuffer.frag (PEELCD_BATCH)
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint max_layers;
  uint max_fragments;
  uint couples_apart, pad0, pad1, pad2;  // as shaders/conservative_batch_resolve.comp's (0 here)
  uvec4 pairs[];  // ID of A's triangle, ID of B's, view, 0
};
layout(std430, binding = 4) readonly buffer Entries { uvec4 entries[]; };  // shaders/batch.inc
layout(std430, binding = 5) buffer ViewLayers { uint view_layers[]; };
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };  // texel t's first fragment
uniform uint texels;  // of the packed k-buffer
#else
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 2, rgba32ui) uniform writeonly uimage2D layer_out;  // capture: layer `emit_layer`

layout(binding = 0) uniform usamplerBuffer count_tex;
layout(binding = 1) uniform usamplerBuffer fragment_tex;  // shaders/abuffer.frag
// The corners each object was drawn from (x, y, z, ID; three per triangle in draw order, as
// arrays or as a rigid shape's 3t + k): a layer's ID is its triangle's provoking (last) corner's.
layout(binding = 2) uniform usamplerBuffer corners_a;
layout(binding = 3) uniform usamplerBuffer corners_b;
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint max_layers;     // the most layers of any texel
  uint max_fragments;  // the most fragments of a texel that had more than `slots` or than
                       // PEELCD_GPU_RESOLVE_DEPTH; else 0
  uvec2 pairs[];
};

uniform float epsilon_window;
uniform float slope;
uniform int resolution;
uniform uint slots;
uniform bool full_peel;
uniform uint first_object;  // alternate: the object of layer 0
uniform bool append_pcs;
uniform int emit_layer;     // -1: none
#endif

void test_pair(uvec4 t0, uvec4 t1, float epsilon_window, float slope, uint view) {
  float spread = abs(uintBitsToFloat(t1.z) - uintBitsToFloat(t0.z)) +
                 abs(uintBitsToFloat(t1.w) - uintBitsToFloat(t0.w));
  if (!pcs_within_epsilon(uintBitsToFloat(t0.x), uintBitsToFloat(t1.x), spread, epsilon_window, slope)) return;
  uint id0 = (t0.y & 0x7fffffffu) - 1u, id1 = (t1.y & 0x7fffffffu) - 1u;
  uint slot = atomicAdd(count, 1u);
  if (slot >= capacity) return;
#ifdef PEELCD_BATCH
  pairs[slot] = (t0.y >> 31) == 0u ? uvec4(id0, id1, view, 0u) : uvec4(id1, id0, view, 0u);
#else
  pairs[slot] = (t0.y >> 31) == 0u ? uvec2(id0, id1) : uvec2(id1, id0);
#endif
}

void main() {
#ifdef PEELCD_BATCH
  uint texel = gl_GlobalInvocationID.x;
  if (texel >= texels) return;
  uint n = texelFetch(count_tex, int(texel)).x;
  if (n == 0u) return;
  // Deeper than one invocation resolves: the host resolves the batch (gl/batch.cpp).
  if (n > uint(PEELCD_GPU_RESOLVE_DEPTH)) {
    atomicMax(max_fragments, n);
    return;
  }
  uint begin = offsets[texel], end = begin + n, step = 1u;
  uint view = entries[texelFetch(fragment_tex, int(begin)).y & 0x7fffffffu].y >> 1;
  uint flags = uint(views[view].info.z);
  bool full_peel = (flags & 2u) != 0u, append_pcs = true;
  uint first_object = flags & 1u;
  float epsilon_window = views[view].box_lo.w, slope = views[view].box_hi.w;
#else
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= resolution || p.y >= resolution) return;
  uint texels = uint(resolution) * uint(resolution);
  uint texel = uint(p.y) * uint(resolution) + uint(p.x);
  uint n = texelFetch(count_tex, int(texel)).x;
  if (n > slots || n > uint(PEELCD_GPU_RESOLVE_DEPTH)) {
    // Some fragments were not stored (n > slots: the host grows and redraws), or the texel is
    // deeper than one invocation resolves (the host resolves the view): no layers from here.
    atomicMax(max_fragments, n);
    return;
  }
  uint begin = texel, end = n * texels + texel, step = texels, view = 0u;
#endif
  uvec4 prev = uvec4(0u), run_start = uvec4(0u);
  int k = 0;
  // Fragments per texel are few: each layer rescans them for the first, in (depth, object,
  // draw order) order, of the wanted object strictly behind the previous layer.
  uint flip = full_peel ? 0u : (first_object << 31);
  for (;; ++k) {
    uint want = full_peel ? 2u : ((first_object + uint(k)) & 1u);
    float prev_z = uintBitsToFloat(prev.x);
    uint prev_rank = (prev.y ^ flip) >> 31;
    bool found = false;
    uvec4 best = uvec4(0u);
    for (uint i = begin; i < end; i += step) {
      uvec4 f = texelFetch(fragment_tex, int(i));
      float z = uintBitsToFloat(f.x);
      if (k > 0 && !(z > prev_z || (z == prev_z && ((f.y ^ flip) >> 31) > prev_rank))) continue;
      if (want != 2u && (f.y >> 31) != want) continue;
      // Equal depth: the lower rank, then the earlier draw wins: (f.y ^ flip)'s order.
      if (!found || z < uintBitsToFloat(best.x) || (z == uintBitsToFloat(best.x) && (f.y ^ flip) < (best.y ^ flip))) {
        best = f;
        found = true;
      }
    }
    if (!found) break;
    uint object = best.y >> 31;
#ifdef PEELCD_BATCH
    uint id = entries[best.y & 0x7fffffffu].z;
#else
    uint corner = 3u * (best.y & 0x7fffffffu) + 2u;
    uint id = object == 0u ? texelFetch(corners_a, int(corner)).w : texelFetch(corners_b, int(corner)).w;
#endif
    uvec4 layer = uvec4(best.x, (object << 31) | (id + 1u), best.z, best.w);
#ifndef PEELCD_BATCH
    if (k == emit_layer) imageStore(layer_out, p, layer);
#endif
    if (k > 0 && append_pcs) {
      bool switched = (prev.y >> 31) != (layer.y >> 31);
      if (switched) test_pair(prev, layer, epsilon_window, slope, view);
      if (full_peel) {
        if (run_start.y == 0u) run_start = prev;
        if (switched) {
          if (run_start != prev) test_pair(run_start, layer, epsilon_window, slope, view);
          run_start = layer;
        }
      }
    }
    prev = layer;
  }
  if (uint(k) > max_layers) atomicMax(max_layers, uint(k));
#ifdef PEELCD_BATCH
  atomicMax(view_layers[view], uint(k));
#endif
}
