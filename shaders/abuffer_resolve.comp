#version 450 core
// Single-pass peeling, step 2: per texel, the layers of design.md recovered from the fragment
// list, exactly as the multi-pass peel (shaders/peel.frag) builds them: layer 0 is the nearest
// fragment of the first object (alternate) or of both (full); layer k+1 the nearest fragment of
// the next object (alternate) or of either (full) strictly behind layer k; the texel ends at the
// first layer with no such fragment. Depth ties go to the earlier-drawn fragment, as GL_LESS does
// in primitive order: object A's draw before B's, then the lower primitive index.
// The PCS test between adjacent layers is shaders/pcs.comp's, run start included.
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 1, r32ui) uniform readonly uimage2D heads;
layout(binding = 2, rgba32ui) uniform writeonly uimage2D layer_out;  // capture: layer `emit_layer`

struct Node {
  uvec4 layer;
  uint primitive;
  uint next;
  uint pad0, pad1;
};
layout(std430, binding = 1) buffer NodeBuffer {
  uint node_count;
  uint node_capacity;
  uint max_layers;  // the most layers of any texel
  uint pad;
  Node nodes[];
};
layout(std430, binding = 0) buffer PcsBuffer {
  uint count;
  uint capacity;
  uint pad0, pad1;
  uvec2 pairs[];
};

uniform float epsilon_window;
uniform float slope;
uniform int resolution;
uniform bool full_peel;
uniform uint first_object;  // alternate: the object of layer 0
uniform bool append_pcs;
uniform int emit_layer;     // -1: none

void test_pair(uvec4 t0, uvec4 t1) {
  float dz = abs(uintBitsToFloat(t1.x) - uintBitsToFloat(t0.x));
  float spread = abs(uintBitsToFloat(t1.z) - uintBitsToFloat(t0.z)) +
                 abs(uintBitsToFloat(t1.w) - uintBitsToFloat(t0.w));
  if (!(dz < epsilon_window + slope * spread)) return;
  uint id0 = (t0.y & 0x7fffffffu) - 1u, id1 = (t1.y & 0x7fffffffu) - 1u;
  uint slot = atomicAdd(count, 1u);
  if (slot < capacity) pairs[slot] = (t0.y >> 31) == 0u ? uvec2(id0, id1) : uvec2(id1, id0);
}

// Is fragment (a, pa) drawn before (b, pb) at equal depth, or nearer?
bool before(uvec4 a, uint pa, uvec4 b, uint pb) {
  float za = uintBitsToFloat(a.x), zb = uintBitsToFloat(b.x);
  if (za != zb) return za < zb;
  if ((a.y >> 31) != (b.y >> 31)) return (a.y >> 31) < (b.y >> 31);
  return pa < pb;
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= resolution || p.y >= resolution) return;
  uint head = imageLoad(heads, p).x;
  uvec4 prev = uvec4(0u), run_start = uvec4(0u);
  int k = 0;
  // Lists are short (a few fragments per texel): each layer rescans the texel's list for the
  // first fragment, in (depth, object, primitive) order, of the wanted object strictly behind
  // the previous layer. (Sorting the list once in registers was slower on llvmpipe.)
  for (;; ++k) {
    uint want = full_peel ? 2u : ((first_object + uint(k)) & 1u);
    bool found = false;
    uvec4 best = uvec4(0u);
    uint best_prim = 0u;
    for (uint i = head; i != 0xffffffffu; i = nodes[i].next) {
      uvec4 d = nodes[i].layer;
      if (want != 2u && (d.y >> 31) != want) continue;
      if (k > 0 && !(uintBitsToFloat(d.x) > uintBitsToFloat(prev.x))) continue;
      uint q = nodes[i].primitive;
      if (!found || before(d, q, best, best_prim)) {
        best = d;
        best_prim = q;
        found = true;
      }
    }
    if (!found) break;
    if (k == emit_layer) imageStore(layer_out, p, best);
    if (k > 0 && append_pcs) {
      bool switched = (prev.y >> 31) != (best.y >> 31);
      if (switched) test_pair(prev, best);
      if (full_peel) {
        if (run_start.y == 0u) run_start = prev;
        if (switched) {
          if (run_start != prev) test_pair(run_start, best);
          run_start = best;
        }
      }
    }
    prev = best;
  }
  if (k > 0) atomicMax(max_layers, uint(k));
}
