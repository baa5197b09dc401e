#version 450 core
// Batched views (gl/batch.cpp), GPU resolve: the count pass's per-texel counts turned into the
// compact k-buffer's offsets on the GPU (an exclusive prefix sum), so that no per-texel data
// crosses the bus; only the total comes back (4 bytes). Three dispatches of this program (`pass`):
//   0. per block of 1024 texels (256 invocations, 4 texels each): the block's exclusive scan
//      into offsets[], its sum into blocks[];
//   1. one work group: the blocks' sums scanned in place (exclusive), the total into the header;
//   2. every texel's offset moved by its block's.
// Integer sums: the offsets the host's loop computes.
layout(local_size_x = 256) in;

layout(std430, binding = 2) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 6) buffer Offsets { uint offsets[]; };
layout(std430, binding = 11) buffer Blocks { uint blocks[]; };
layout(std430, binding = 12) buffer Header { uint total; };

uniform uint texels;
uniform uint block_count;
uniform int pass;

shared uint partial[256];

// The work group's exclusive scan of `value` into partial[]; returns the group's sum.
uint scan_group(uint value) {
  uint i = gl_LocalInvocationID.x;
  partial[i] = value;
  barrier();
  for (uint d = 1u; d < 256u; d <<= 1) {
    uint add = i >= d ? partial[i - d] : 0u;
    barrier();
    partial[i] += add;
    barrier();
  }
  uint sum = partial[255];
  uint before = partial[i] - value;
  barrier();
  partial[i] = before;
  barrier();
  return sum;
}

void main() {
  uint i = gl_LocalInvocationID.x;
  uint first = gl_WorkGroupID.x * 1024u + 4u * i;  // passes 0 and 2: this invocation's texels
  if (pass == 0) {
    uint c[4];
    uint mine = 0u;
    for (uint k = 0u; k < 4u; ++k) {
      c[k] = first + k < texels ? counts[first + k] : 0u;
      mine += c[k];
    }
    uint sum = scan_group(mine);
    uint at = partial[i];
    for (uint k = 0u; k < 4u; ++k) {
      if (first + k < texels) offsets[first + k] = at;
      at += c[k];
    }
    if (i == 0u) blocks[gl_WorkGroupID.x] = sum;
  } else if (pass == 1) {
    uint carry = 0u;
    bool wrapped = false;  // more fragments than 32 bits count: the host draws view by view
    for (uint start = 0u; start < block_count; start += 256u) {
      uint sum = scan_group(start + i < block_count ? blocks[start + i] : 0u);
      if (start + i < block_count) blocks[start + i] = carry + partial[i];
      wrapped = wrapped || carry + sum < carry;
      carry += sum;
    }
    if (i == 0u) total = wrapped ? 0xffffffffu : carry;
  } else {
    uint add = blocks[gl_WorkGroupID.x];
    for (uint k = 0u; k < 4u; ++k)
      if (first + k < texels) offsets[first + k] += add;
  }
}
