#version 450 core
// PCS between two adjacent layers: a texel where both layers hold a fragment and
// |z(k+1) - z(k)| < epsilon appends the ID pair (ID of A, ID of B) to an append buffer.
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform usampler2D layer_k;
layout(binding = 1) uniform usampler2D layer_k1;
uniform float epsilon_window;  // epsilon in window-depth units
uniform bool k1_is_a;          // layer k+1 belongs to object A (else to B)
uniform int resolution;

layout(std430, binding = 0) buffer PcsBuffer {
  uint count;     // total appended, may exceed capacity (the host then grows and reruns)
  uint capacity;  // pairs that fit in `pairs`
  uint pad0, pad1;
  uvec2 pairs[];
};

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= resolution || p.y >= resolution) return;
  uvec2 t0 = texelFetch(layer_k, p, 0).xy;
  uvec2 t1 = texelFetch(layer_k1, p, 0).xy;
  if (t0.y == 0u || t1.y == 0u) return;
  float dz = abs(uintBitsToFloat(t1.x) - uintBitsToFloat(t0.x));
  if (!(dz < epsilon_window)) return;
  uint slot = atomicAdd(count, 1u);
  if (slot < capacity) pairs[slot] = k1_is_a ? uvec2(t1.y - 1u, t0.y - 1u) : uvec2(t0.y - 1u, t1.y - 1u);
}
