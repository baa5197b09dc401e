#pragma once
// Proximity (DetectOptions::margin; docs/design.md, "Proximity"): the triangle pairs of two
// objects (or of one object with self-collision, not sharing a vertex) whose distance is at most
// a margin, each with its distance and closest points, and per object pair the least distance
// with its two witness points. A pair that meets has distance 0.
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/pair_outcomes.h"

#include <limits>
#include <vector>

namespace peelcd {


// The distance of two triangles and their closest points (p on a, q on b): 0 (and a common point)
// when they meet (the exact test); else the least of the six corner-to-triangle and nine
// edge-to-edge distances, computed in double (relative error a few units in the last place of
// the coordinates' magnitude over the distance).
double triangle_distance(const TriangleCorners& a, const TriangleCorners& b, Vec3& p, Vec3& q);

// Every triangle pair of `a` and `b` within `margin` (a tree over b's triangles, each of a's
// boxes grown by the margin: no pair within it is missed).
Proximity near_pairs(const Mesh& a, const Mesh& b, double margin);
// Every pair of distinct, non-adjacent triangles of `m` within `margin` (`rep`: the vertex
// representatives of vertex_representatives(): adjacent triangles share one).
Proximity near_self_pairs(const Mesh& m, const std::vector<std::uint32_t>& rep, double margin);
// The same with the tree over b's (or m's) triangles built by the caller (Bvh::build over the
// same mesh): a frame builds each object's tree once for all its pairs.
Proximity near_pairs(const Mesh& a, const Mesh& b, const Bvh& tree_b, double margin);
Proximity near_self_pairs(const Mesh& m, const Bvh& tree, const std::vector<std::uint32_t>& rep, double margin);
// The pairs within `margin` among `candidates` (pack_pair(tri_a, tri_b)): a stage's candidates
// when every pair within the margin is among them (the image stage's conservative PCS with
// triangles grown by half the margin, the exact path's boxes grown by the margin).
Proximity near_among(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates, double margin);

}  // namespace peelcd
