#pragma once
// Object-level broad phase: sort-and-sweep on x over per-object world AABBs.
#include "peelcd/core/aabb.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace peelcd {

// overlapping_pairs()' storage, kept by a caller that sweeps every frame (no allocation in
// steady state).
struct SweepScratch {
  std::vector<std::size_t> order;  // the non-empty boxes, by their lower x
  std::vector<double> lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;  // their bounds in that order
  std::vector<std::uint64_t> keys, spare;  // the pairs packed (i << 32 | j), sorted
};

// Pairs (i, j), i < j, whose boxes overlap (closed boxes), sorted lexicographically.
std::vector<std::pair<std::size_t, std::size_t>> overlapping_pairs(const std::vector<Aabb>& boxes);
// The same into `out`.
void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<std::size_t, std::size_t>>& out,
                       SweepScratch& scratch);

}  // namespace peelcd
