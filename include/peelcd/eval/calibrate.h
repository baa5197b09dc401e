#pragma once
// Calibration of the stage router (Stage::automatic, docs/router.md):
// one-ROI scenes of growing size and density timed through the image stage and through the
// exact CPU path on the same detector, and the two linear cost models fitted to them.
#include "peelcd/core/image/detector.h"

#include <functional>
#include <string>
#include <vector>

namespace peelcd {

struct CalibrationRow {
  std::string scene;
  std::size_t triangles = 0;  // triangles of the ROI (both objects) one culling round keeps: the router's n
  int tile = 0;               // the image stage's tile side
  int views = 1;
  double image_ms = 0.0, exact_ms = 0.0;  // medians of the stage's part of the frame
  std::size_t image_candidates = 0, exact_candidates = 0;
};

struct Calibration {
  std::vector<CalibrationRow> rows;
  StageCost image, exact;  // fitted (least squares of the relative error, coefficients kept >= 0)
  // With the fitted models and with the ones in use (ImageStage::cost(), exact_path_cost()):
  // the rows where the router picks the slower stage, and the time lost over all rows.
  std::size_t wrong_fitted = 0, wrong_in_use = 0;
  double lost_ms_fitted = 0.0, lost_ms_in_use = 0.0, best_ms = 0.0;
};

// The calibration scenes: pairs of UV spheres (64 to 33,000 triangles, shallow and deep
// overlap), a sphere and its copy at the same pose, and the fixtures' bunny and dragon at three
// offsets (`meshes_dir`: fixtures/meshes). Each has exactly one overlapping pair.
std::vector<std::pair<std::string, std::vector<Object>>> calibration_scenes(const std::string& meshes_dir);

// Times every scene at every budget in `budgets` `repeat` times per stage (after one untimed
// frame) and fits the models.
Calibration calibrate(Detector& detector, const std::string& meshes_dir, const std::vector<int>& budgets, int repeat);

// One stage setting against another (the GL stage's coverage: raster or compute): the image
// stage's part of the frame (as calibrate() times it) and its GPU pass time (Timings::gpu_raster
// + gpu_compute, with pass timing on) on every calibration scene at `budget`, each of `variants`
// settings applied by `use(k)`, in turns each frame after one untimed frame each; medians.
struct VariantRow {
  std::string scene;
  std::vector<double> ms, gpu_ms;  // per variant
};
std::vector<VariantRow> time_variants(Detector& detector, const std::string& meshes_dir, int budget, int repeat,
                                      int variants, const std::function<void(int)>& use);

// The same on the World's image route (Stage::image, every pair drawn; batched where the World
// batches): a pile of 200 balls (rigid and deforming) and two crossing waving spheres of 82,368
// triangles each, `repeat` frames of each setting in turns after one untimed frame each; the
// World's frame ms (`World::collide`'s timings.total: the bodies are brought outside it).
std::vector<VariantRow> time_world_variants(Detector& detector, int repeat, int variants,
                                            const std::function<void(int)>& use);

// Large meshes (two crossing rigid spheres, make_crossing_spheres(), at `stacks` bands): what the
// routers predict against what the frame takes, through the frame API (Stage::automatic: the
// route's predicted ms, its scan included, against the frame's total) and through the World (its
// exact path's prediction from the candidates against its narrow phase; its whole frame beside).
struct LargeMeshRow {
  int stacks = 0;
  std::size_t triangles = 0;    // both spheres
  std::size_t kept = 0;         // the frame API's triangles after one culling round
  double frame_predicted_ms = 0.0, frame_ms = 0.0;
  std::size_t candidates = 0;   // the World's candidate couples
  double world_predicted_ms = 0.0, world_narrow_ms = 0.0, world_ms = 0.0;
};
std::vector<LargeMeshRow> calibrate_large_meshes(Detector& detector, const std::vector<int>& stacks, int repeat);

}  // namespace peelcd
