#pragma once
// Calibration of the stage router (Stage::automatic, docs/performance.md "The stage router"):
// one-ROI scenes of growing size and density timed through the image stage and through the
// exact CPU path on the same detector, and the two linear cost models fitted to them.
#include "peelcd/core/detector.h"

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

}  // namespace peelcd
