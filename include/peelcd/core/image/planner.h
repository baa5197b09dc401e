#pragma once
// The frame's planning, shared by the frame API (Detector) and the World: the stage router (one
// cost model: StageCost, per backend and per exact path), the views a ROI is peeled along and
// the tiles ROIs share a texture budget by.

#include "peelcd/core/frame.h"
#include "peelcd/core/image/image_stage.h"

#include <vector>

namespace peelcd {

// The World's exact path per candidate couple once its trees have found it (the narrow phase),
// us: `peelcd calibrate` prints it against what it measures.
constexpr double kWorldCandidateUs = 0.12;

// The World's exact path as a cost model: kWorldCandidateUs per candidate couple, no scan (its
// trees replace culling). The frame API's is exact_path_cost() (peelcd/core/image/image_stage.h).
StageCost world_exact_cost();

// One pair's route (Stage::automatic), or the one the options force.
struct Route {
  bool exact = false;              // to the exact CPU path; else to the image stage
  double predicted_exact_ms = 0.0;
  double predicted_image_ms = 0.0;
};

// The stage router, for the frame API and the World alike: `work` triangles (or candidate
// couples, for the World) go through the exact path at exact.predict_ms(work, 0) or through
// `views` views of the image stage at image.predict_ms(work, tile^2) each; `scanned` triangles
// are read by both paths (exact.scan_us each, part of both predictions). The cheaper wins; a
// tie goes to the exact path. Stage::exact and Stage::image decide alone (predictions 0).
// Deterministic: the models are constants, not timings.
Route route_pair(const DetectOptions& options, const StageCost& exact, const StageCost& image, double scanned,
                 double work, int tile);

// A margin wider than this share of a pair's ROI (its longest side) sends the pair to the exact
// path whatever the stage asked: the image stage grows every triangle by half the margin, so
// each fragment covers a growing share of the view and the PCS tend to every couple (the
// default scene at a margin of 0.24 of its size: 1,467 layers, 1.9M PCS, 5.5-6.3 GB and twice
// the exact path's time, which took 2.2 GB for the same near pairs), and a view grown beyond
// float range (a margin near 1e154 and up) rasterizes nothing. The proximity tests' margins (2%
// of the scene) stay under it. PairResult::margin_fallback says where it acted.
constexpr double kImageMarginShare = 0.125;
bool margin_too_wide_for_image(const DetectOptions& options, const Aabb& roi);


// The view frames a ROI is peeled along for `options` (1, 2 or 3 of them).
std::vector<ViewFrame> fused_view_frames(const DetectOptions& options);
// The same into `out` (room for 3); returns the count. Allocates nothing.
std::size_t fused_view_frames(const DetectOptions& options, ViewFrame out[3]);

// Side of each ROI's tile when `roi_count` ROIs share a budget x budget texture equally: the
// largest power-of-two fraction of `budget` such that the tiles fit (1 ROI: budget; 2-4:
// budget/2; ...), never below 16. The paper's way, kept for Cull::box.
int tile_resolution(int budget, std::size_t roi_count);

// Resolution by need: `needs[i]` is the side ROI i asks for (edge_tile_resolution() with the
// whole budget as its cap). When the squares fit in budget x budget texels they are granted;
// otherwise every side is scaled by the same factor so that they fit, rounded down to a multiple
// of 16, never below 16. Writes `tiles` (same size as `needs`).
void allocate_tiles(int budget, const std::vector<int>& needs, std::vector<int>& tiles);

// The tile side for a ROI whose region (the culled box) is `region` and whose triangles' median
// edge is `median_edge`: `edge_texels` texels per median edge across the region's longest side,
// rounded up to a multiple of 16, at least 16, at most `share` (the budget's tile). `share`
// itself when edge_texels is 0 or the edge is not positive and finite.
int edge_tile_resolution(int share, const Aabb& region, double median_edge, double edge_texels);

// Which path tested a pair, in one word: "exact" (the exact CPU path), "image" (the image
// stage's PCS), "exhaustive" (every view fell back to box-overlap tests: no layer, no PCS) or
// "image+exhaustive" (some views did); "none" when culling left no triangle of one object.
const char* pair_path(const PairResult& pair);
// Why, in a sentence (`options`: the frame's).
std::string pair_path_reason(const PairResult& pair, const DetectOptions& options);

}  // namespace peelcd
