#pragma once
// One layer texel, written once: four 32-bit words (an RGBA32UI texel, shaders/peel.frag; a
// k-buffer fragment, shaders/abuffer.frag and shaders/conservative.frag):
//   word 0  depth (window units)           conservative stage: lower depth of the interval
//   word 1  object << 31 | ID + 1 (0: empty)
//   word 2  dz/dx (window units per texel)  conservative stage: upper depth of the interval
//   word 3  dz/dy                           conservative stage: 0
// A layer is N*N such texels, row by row from the bottom (GL's order). Used by the k-buffer
// resolve, dumps, the viewer, explain; the GLSL writes the same words.
#include <cstdint>
#include <cstring>
#include <vector>

namespace peelcd::texel {

enum Word : std::size_t { kDepth = 0, kKey = 1, kDzdx = 2, kDzdy = 3, kUpper = 2 };

inline float as_float(std::uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}
inline std::uint32_t bits_of(float f) {
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

// Word `w` of texel `t` of `layer`, and its float value.
inline std::uint32_t word(const std::vector<std::uint32_t>& layer, std::size_t t, Word w) { return layer[4 * t + w]; }
inline float value(const std::vector<std::uint32_t>& layer, std::size_t t, Word w) { return as_float(layer[4 * t + w]); }
inline bool empty(const std::vector<std::uint32_t>& layer, std::size_t t) { return layer[4 * t + kKey] == 0; }
inline std::uint32_t object(const std::vector<std::uint32_t>& layer, std::size_t t) { return layer[4 * t + kKey] >> 31; }
// The ID + 1 (0: empty).
inline std::uint32_t id1(const std::vector<std::uint32_t>& layer, std::size_t t) { return layer[4 * t + kKey] & 0x7fffffffu; }

}  // namespace peelcd::texel
