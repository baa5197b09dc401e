#version 450 core
// Single-pass peeling, step 1: both objects drawn once; every fragment is appended to its
// texel's list (an A-buffer: a node buffer filled through an atomic counter, a head image
// swapped atomically). shaders/abuffer_resolve.comp recovers the layers from the lists.
// A node holds exactly what a peel pass would store for the fragment (shaders/peel.frag) plus
// the primitive's index, which breaks depth ties the way the depth test does in primitive order.
flat in uint v_id;
uniform uint object_bit;  // 0 for object A, 1 for object B

layout(binding = 1, r32ui) uniform coherent uimage2D heads;  // 0xffffffff = empty list

struct Node {
  uvec4 layer;  // as a layer texel: depth bits, object << 31 | ID + 1, dz/dx bits, dz/dy bits
  uint primitive;
  uint next;
  uint pad0, pad1;
};
layout(std430, binding = 1) buffer NodeBuffer {
  uint node_count;     // fragments appended, may exceed capacity (the host grows and redraws)
  uint node_capacity;
  uint max_layers;     // written by the resolve pass
  uint pad;
  Node nodes[];
};

void main() {
  float z = gl_FragCoord.z;
  float gx = dFdx(z), gy = dFdy(z);
  // A peel pass clears depth to 1.0 and tests GL_LESS: a fragment at the far plane never lands.
  if (!(z < 1.0)) return;
  uint i = atomicAdd(node_count, 1u);
  if (i >= node_capacity) return;
  nodes[i].layer = uvec4(floatBitsToUint(z), (object_bit << 31) | (v_id + 1u), floatBitsToUint(gx),
                         floatBitsToUint(gy));
  nodes[i].primitive = uint(gl_PrimitiveID);
  nodes[i].next = imageAtomicExchange(heads, ivec2(gl_FragCoord.xy), i);
}
