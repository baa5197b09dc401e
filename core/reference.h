#pragma once
// Exact all-pairs reference (no sampling): CGAL box_intersection_d over per-triangle boxes, then
// the exact triangle test of narrow_phase.h. It defines nCTP and the miss ratio.
#include "core/mesh.h"

#include <vector>

namespace peelcd {

// Colliding triangle pairs of A and B, packed with pack_pair(triA, triB), sorted.
std::vector<std::uint64_t> exact_colliding_pairs(const Mesh& a, const Mesh& b);

}  // namespace peelcd
