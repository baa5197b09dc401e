#pragma once
// Contact-region culling: before a ROI is peeled, the triangles of each object that cannot touch
// the other object are dropped and the ROI is shrunk to what is left.
//
// The ROI (the overlap of the two objects' boxes) is cut into a grid of cells; each object marks
// the cells its triangles' boxes touch; a triangle is kept only if its box touches a cell the
// other object marked. The box of each object's kept triangles, intersected with the ROI and
// with the other object's, is the new ROI, and the test repeats on it while it drops triangles.
//
// Conservative: two triangles that share a point p both touch the ROI (p lies in both objects'
// boxes) and both touch the cell holding p. Cell indices are floor((x - lo) / size) clamped to
// the grid, computed the same way for every box; that is monotone in x, so two closed boxes that
// overlap always touch a common cell, whatever the rounding. Every colliding pair survives every
// round, and so lies inside every round's box. Only triangles that collide with nothing are
// dropped: removing a surface never hides a contact between two others from the peeling, it only
// removes layers (docs/accuracy.md measures it).
#include "peelcd/core/aabb.h"

#include <cstdint>
#include <vector>

namespace peelcd {

struct CullStats {
  std::size_t in_roi_a = 0, in_roi_b = 0;  // triangles touching the ROI, before culling
  std::size_t kept_a = 0, kept_b = 0;      // after
  int rounds = 0;                          // grid rounds run
};

// Scratch and result of cull_to_contact_region(); reused across calls (no allocation in steady
// state once the largest sizes have been seen).
struct ContactCull {
  std::vector<std::uint32_t> kept_a, kept_b;  // triangle indices kept, ascending
  Aabb box;                                   // the shrunk ROI; empty() when nothing is kept
  double median_edge = 0.0;                   // median of the kept triangles' mean edge lengths
  CullStats stats;

  // Scratch.
  struct Entry {
    std::uint32_t tri;
    std::uint16_t lo[3], hi[3];  // cell range, inclusive
  };
  std::vector<Entry> entries_a, entries_b;
  std::vector<Aabb> boxes_a, boxes_b;  // each entry's triangle box, parallel to entries_*
  std::vector<std::uint64_t> cells_a, cells_b;  // occupancy bitsets
  std::vector<std::uint8_t> outcodes;           // per vertex of the mesh being gathered
  std::vector<double> edges;
};

// Grid cells per round: about kCullCellsPerTriangle times the triangles still in play, at most
// kMaxCullCells; at most kMaxCullRounds rounds (a round that drops nothing ends it).
constexpr int kCullCellsPerTriangle = 4;
constexpr std::size_t kMaxCullCells = std::size_t(1) << 18;
constexpr int kMaxCullRounds = 3;

// Fills `out` with the triangles of `a` and `b` (world space) that may touch the other object
// inside `roi`, the shrunk ROI and the kept triangles' median edge length, after at most
// `max_rounds` rounds (1 to kMaxCullRounds). The detector's exact CPU path stops after one round
// (later rounds cost more than the box overlaps they save there); the image stage takes all of
// them (fewer triangles drawn, a smaller region, a finer tile).
// `margin` > 0 (proximity, DetectOptions::margin): every triangle's box is grown by half the
// margin, so that two triangles within the margin of each other share a cell (their closest
// points' midpoint lies in both grown boxes) and are kept; `roi` is then the overlap of the
// objects' boxes grown by half the margin.
void cull_to_contact_region(const Mesh& a, const Mesh& b, const Aabb& roi, ContactCull& out,
                            int max_rounds = kMaxCullRounds, double margin = 0.0);

}  // namespace peelcd
