#pragma once
// The stage router's cost models in a file (docs/router.md): written by
// `peelcd calibrate --write-costs FILE` with the models it fitted, the backend and the renderer
// they were fitted on; read by `detect`/`simulate`/`bench --costs FILE`, the PEELCD_COSTS
// environment variable (any program that makes its stage with apply_cost_models_from_env()),
// and Python's `World(..., costs=FILE)`. Without one a stage routes by its built-in models.
//
//   {"format": "peelcd.costs/1", "backend": "egl-device", "renderer": "NVIDIA H200/PCIe/SSE2",
//    "fitted": "2026-11-25", "image": {"view_ms": 0.16, "triangle_us": 0.72, "texel_ns": 0},
//    "exact": {"view_ms": 0, "triangle_us": 0.32, "scan_us": 0.055}, "coverage": "raster"}
// ("coverage": optional, the GL stage's conservative coverage calibrate timed faster there.)
#include "peelcd/core/image/image_stage.h"

#include <string>

namespace peelcd {

inline constexpr const char* kCostsFormat = "peelcd.costs/1";

// The file's models (source = `path`). Throws InputError naming the file and the problem (missing,
// malformed, another format, a coefficient missing, negative or not finite).
CostModels read_cost_models(const std::string& path);
// Writes `models` (their backend, renderer; `fitted`: a date) to `path`. Throws InputError.
void write_cost_models(const std::string& path, const CostModels& models, const std::string& fitted);
// Reads `path` and gives its models to `stage`, after checking that they were fitted on the
// stage's backend and renderer: models of another GPU or driver would route by another machine's
// costs. Throws InputError naming the file and both renderers.
void apply_cost_models(ImageStage& stage, const std::string& path);
// apply_cost_models() with $PEELCD_COSTS when it is set and not empty; returns its value.
std::string apply_cost_models_from_env(ImageStage& stage);

}  // namespace peelcd
