#pragma once
// Object-level broad phase: sort-and-sweep on x over per-object world AABBs.
#include "peelcd/core/aabb.h"

#include <utility>
#include <vector>

namespace peelcd {

// Pairs (i, j), i < j, whose boxes overlap (closed boxes), sorted lexicographically.
std::vector<std::pair<std::size_t, std::size_t>> overlapping_pairs(const std::vector<Aabb>& boxes);
// The same into `out`, with `order` as scratch (both reused: no allocation in steady state).
void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<std::size_t, std::size_t>>& out,
                       std::vector<std::size_t>& order);

}  // namespace peelcd
