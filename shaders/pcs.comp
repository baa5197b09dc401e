#version 450 core
// PCS between two adjacent layers: a texel where both layers hold fragments of different
// objects and |z(k+1) - z(k)| < epsilon + slope * (|dgx| + |dgy|) appends the ID pair
// (ID of A, ID of B). The slope term is the depth difference the two surfaces' planes can
// close within `slope` texels of the centre; slope = 0 is the paper's constant epsilon.
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform usampler2D layer_k;
layout(binding = 1) uniform usampler2D layer_k1;
uniform float epsilon_window;  // epsilon in window-depth units
uniform float slope;           // texels
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
  uvec4 t0 = texelFetch(layer_k, p, 0);
  uvec4 t1 = texelFetch(layer_k1, p, 0);
  if (t0.y == 0u || t1.y == 0u) return;
  uint object0 = t0.y >> 31, object1 = t1.y >> 31;
  if (object0 == object1) return;
  float dz = abs(uintBitsToFloat(t1.x) - uintBitsToFloat(t0.x));
  float spread = abs(uintBitsToFloat(t1.z) - uintBitsToFloat(t0.z)) +
                 abs(uintBitsToFloat(t1.w) - uintBitsToFloat(t0.w));
  if (!(dz < epsilon_window + slope * spread)) return;
  uint id0 = (t0.y & 0x7fffffffu) - 1u, id1 = (t1.y & 0x7fffffffu) - 1u;
  uint slot = atomicAdd(count, 1u);
  if (slot < capacity) pairs[slot] = object0 == 0u ? uvec2(id0, id1) : uvec2(id1, id0);
}
