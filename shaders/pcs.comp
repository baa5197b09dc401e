#version 450 core
// PCS between two adjacent layers k and k+1 of different objects: the texel appends the ID pair
// (ID of A, ID of B) when |z(k+1) - z(k)| < epsilon + slope * (|dgx| + |dgy|). The slope term
// is the depth difference the two surfaces' planes can close within `slope` texels of the
// centre; slope = 0 is the paper's constant epsilon.
//
// Full peeling also tests layer k+1 against the first surface of the run of same-object layers
// that ends at layer k (`run_start`): alternate peeling pairs exactly those first surfaces
// (A1 A2 B: alternate pairs A1-B, adjacency pairs A2-B), so full mode is a superset of it.
#include "peelcd/core/image/pcs_test.inc"  // pcs_within_epsilon, pcs_intervals_overlap (shared with C++)

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform usampler2D layer_k;
layout(binding = 1) uniform usampler2D layer_k1;
layout(binding = 0, rgba32ui) uniform uimage2D run_start;  // zero = not started
uniform float epsilon_window;  // epsilon in window-depth units
uniform float slope;           // texels
uniform int resolution;
uniform bool track_runs;       // full peeling

layout(std430, binding = 0) buffer PcsBuffer {
  uint count;     // total appended, may exceed capacity (the host then grows and reruns)
  uint capacity;  // pairs that fit in `pairs`
  uint pad0, pad1;
  uvec2 pairs[];
};

void test_pair(uvec4 t0, uvec4 t1) {
  float spread = abs(uintBitsToFloat(t1.z) - uintBitsToFloat(t0.z)) +
                 abs(uintBitsToFloat(t1.w) - uintBitsToFloat(t0.w));
  if (!pcs_within_epsilon(uintBitsToFloat(t0.x), uintBitsToFloat(t1.x), spread, epsilon_window, slope)) return;
  uint id0 = (t0.y & 0x7fffffffu) - 1u, id1 = (t1.y & 0x7fffffffu) - 1u;
  uint slot = atomicAdd(count, 1u);
  if (slot < capacity) pairs[slot] = (t0.y >> 31) == 0u ? uvec2(id0, id1) : uvec2(id1, id0);
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= resolution || p.y >= resolution) return;
  uvec4 t0 = texelFetch(layer_k, p, 0);
  uvec4 t1 = texelFetch(layer_k1, p, 0);
  if (t0.y == 0u || t1.y == 0u) return;
  bool switched = (t0.y >> 31) != (t1.y >> 31);
  if (switched) test_pair(t0, t1);
  if (!track_runs) return;
  uvec4 rs = imageLoad(run_start, p);
  if (rs.y == 0u) rs = t0;  // the first run starts at layer 0
  if (switched) {
    if (rs != t0) test_pair(rs, t1);
    rs = t1;
  }
  imageStore(run_start, p, rs);
}
