#pragma once
// The certified filter of the GPU resolve (peelcd/core/image/certified_apart.inc) in C++: the same
// source over a float vec3 with GLSL's operations, for its tests and for callers that hold float
// corners. certified_apart() returns true only when the true triangles (each corner within its
// error bound of the float one given) are certainly more than `reach` apart.
#include <algorithm>
#include <cmath>

namespace peelcd::certified {

struct vec3 {
  float x, y, z;
};
inline vec3 operator+(vec3 a, vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline vec3 operator-(vec3 a, vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline float dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline vec3 cross(vec3 a, vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline vec3 abs(vec3 a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }
inline float min(float a, float b) { return std::min(a, b); }
inline float max(float a, float b) { return std::max(a, b); }
inline vec3 max(vec3 a, vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }

#define PEELCD_PCS_FN inline
#include "peelcd/core/image/certified_apart.inc"
#undef PEELCD_PCS_FN

}  // namespace peelcd::certified
