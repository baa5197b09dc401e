#pragma once
// Penetration depth (DetectOptions::depth; docs/design.md, "Penetration depth"): for two closed
// objects that collide or contain one another, a unit direction n and a depth d such that A
// translated by d n shares no interior with B (touching allowed) and no shorter translation
// along n does.
//
// Along one direction the depth is decided from the triangles: in a frame where n is the z axis,
// every couple (a triangle of A, a triangle of B) whose shadows overlap meets for the
// translations s in one interval, the vertical line through the origin across the convex hull of
// the nine corner differences; for a direction in general position (every candidate is turned by
// kDepthPerturbation radians off any face it may be parallel to) the surfaces cross for every s
// strictly inside it. Walking s up from 0 across the union of these intervals, the first gap in
// which neither object contains the other (exact point-in-mesh tests) begins at d.
//
// The direction: the least d among candidates (the contacts' area-weighted normals of B and of
// A, the intersection volume's gradient, the centroids' difference, the six axes) and
// kDepthGlobalDirections directions spread over the sphere, then a local search around each of
// the kDepthStarts best of them (rotations of a quarter radian, halved when no neighbour
// improves; at most kDepthLocalEvaluations a start). At most 12 + 48 + 3 x 64 = 252 directions:
// the cost is bounded by that many one-direction evaluations (each over the couples whose
// translations meet). The result is a least found, not a proven least: tests/eval/test_depth.cpp
// holds it within 1.05x of a 300-direction search on real meshes at several poses.
// The pair is computed in a canonical order of the two meshes, so that swapping A and B gives
// (-n, d) exactly.
#include "peelcd/core/mesh.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/pair_outcomes.h"

#include <string>
#include <vector>

namespace peelcd {

// How far a candidate direction is turned to put it in general position (radians).
constexpr double kDepthPerturbation = 1e-7;
// The search's budget (see above).
constexpr int kDepthGlobalDirections = 48;
constexpr int kDepthStarts = 3;
constexpr int kDepthLocalEvaluations = 64;


// The least s >= 0 such that A translated by s n shares no interior with B (touching allowed),
// both closed; n is used as given (unit). `bound` receives the rounding bound of the result.
double depth_along(const Mesh& a, const Mesh& b, const Vec3& n, double* bound = nullptr);

// The pair's direction and depth (see above). `contacts`: the pair's colliding triangle pairs
// (tri_a of A, tri_b of B), for the candidates; may be empty (containment).
PenetrationDepth penetration_depth(const Mesh& a, const Mesh& b, const std::vector<Contact>& contacts);

}  // namespace peelcd
