#pragma once
// Procedural meshes for tests and generated scenes. Closed meshes are wound counter-clockwise
// seen from outside.
#include "peelcd/core/mesh.h"

#include <functional>

namespace peelcd {

// Axis-aligned box [lo, hi]: 8 vertices, 12 triangles.
Mesh make_box(const Vec3& lo, const Vec3& hi);

// UV sphere: `stacks` >= 2 latitude bands, `slices` >= 3 longitude sectors;
// 2 + (stacks - 1) * slices vertices, 2 * slices * (stacks - 1) triangles.
Mesh make_uv_sphere(const Vec3& center, double radius, int stacks, int slices);

// Open grid spanning origin + s*e1 + t*e2, s, t in [0, 1]; n1 x n2 quads, 2 triangles each.
Mesh make_grid(const Vec3& origin, const Vec3& e1, const Vec3& e2, int n1, int n2);

// A surface over an nu x nv grid of quads, two triangles each ((i, j), (i+1, j), (i+1, j+1) and
// (i, j), (i+1, j+1), (i, j+1)), its vertex (i, j) at `at(i / nu, j / nv)`, row after row.
Mesh make_grid_surface(int nu, int nv, const std::function<Vec3(double, double)>& at);

// A unit sheet (6 n^2 triangles, n across) folded over itself along x = 1: its bottom layer at
// z = 0 over [0, 1]^2, a half-circle crease, its top layer at z = `fold` lowered by a bump `sag`
// deep over the bottom's middle (it passes through the bottom layer where sag > fold). Open.
Mesh make_folded_sheet(int n, double fold, double sag);

// A cloth of 2 n^2 triangles (n across) draped over a ball of radius about 1 and crumpled, at time
// `t`: its parameter square folded by tangential waves (so layers of it overlap) and each layer
// at its own height over the ball (so the layers pass through one another). Open. At n = 224
// (100,352 triangles) about 33,000 self-intersecting pairs (not sharing a vertex); the folds
// drift as t grows (0.15 a frame in peelcd bench cloth-crumpled).
Mesh make_crumpled_cloth(int n, double t);

}  // namespace peelcd
