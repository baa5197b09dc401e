#pragma once
// Exact all-pairs reference (no sampling): CGAL box_intersection_d over per-triangle boxes, then
// the exact triangle test of narrow_phase.h. It defines nCTP and the miss ratio.
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/exact/self.h"

#include <memory>
#include <vector>

namespace peelcd {

// Colliding triangle pairs of A and B, packed with pack_pair(triA, triB), sorted.
std::vector<std::uint64_t> exact_colliding_pairs(const Mesh& a, const Mesh& b);

// The exact reference of a frame's pair of objects `ia` and `ib`: exact_colliding_pairs() of
// their meshes, or exact_self_pairs() (with `adjacency`) for a self pair (ia == ib).
std::vector<std::uint64_t> exact_pair_reference(const std::vector<Object>& objects, std::size_t ia, std::size_t ib,
                                                SelfAdjacency adjacency);

// Appends pack_pair(triA, triB) for every triangle of `ta` (of A) and of `tb` (of B) whose
// closed boxes overlap, by a sweep along x: the candidates of the exact CPU path (no image stage).
// With `scratch`, the boxes' storage is kept there from call to call (a frame loop allocates
// nothing once it has grown). `margin` > 0 grows A's boxes by it: every couple within the
// margin of each other is among the pairs (proximity).
class BoxScratch {
 public:
  BoxScratch();
  ~BoxScratch();
  struct Impl;
  std::unique_ptr<Impl> impl;
};
void box_overlap_pairs(const Mesh& a, const std::vector<std::uint32_t>& ta, const Mesh& b,
                       const std::vector<std::uint32_t>& tb, std::vector<std::uint64_t>& out,
                       BoxScratch* scratch = nullptr, double margin = 0.0);

// The same pairs through CGAL's box_intersection_d (the benchmark's CGAL peer; the exact
// reference uses it too). box_overlap_pairs() sweeps along x instead: faster on the few thousand
// boxes of a ROI (docs/performance.md).
void cgal_box_overlap_pairs(const Mesh& a, const std::vector<std::uint32_t>& ta, const Mesh& b,
                            const std::vector<std::uint32_t>& tb, std::vector<std::uint64_t>& out);

// Reported contacts against the exact set: every miss and every false contact counts.
struct Score {
  std::size_t exact = 0, found = 0, missed = 0, false_contacts = 0;
  double miss_ratio() const { return exact ? double(missed) / double(exact) : 0.0; }
};
Score score_contacts(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported);

}  // namespace peelcd
