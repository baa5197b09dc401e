#pragma once
// Procedural meshes for tests and generated scenes. Closed meshes are wound counter-clockwise
// seen from outside.
#include "peelcd/core/mesh.h"

namespace peelcd {

// Axis-aligned box [lo, hi]: 8 vertices, 12 triangles.
Mesh make_box(const Vec3& lo, const Vec3& hi);

// UV sphere: `stacks` >= 2 latitude bands, `slices` >= 3 longitude sectors;
// 2 + (stacks - 1) * slices vertices, 2 * slices * (stacks - 1) triangles.
Mesh make_uv_sphere(const Vec3& center, double radius, int stacks, int slices);

// Open grid spanning origin + s*e1 + t*e2, s, t in [0, 1]; n1 x n2 quads, 2 triangles each.
Mesh make_grid(const Vec3& origin, const Vec3& e1, const Vec3& e2, int n1, int n2);

}  // namespace peelcd
