#pragma once
// The options of a frame as JSON: one writer, used by the result JSON (detect --json), the dump
// metadata (meta.json) and anything else that records a configuration. The reader is the scene
// parser (peelcd/io/scene.h): the same keys, each checked with a message that names it; the
// ranges themselves are checked once, by validate_options() (peelcd/core/detector.h).
//   detect options: theta, phi, resolution, budget, ids, epsilon, peel, slope, views, cull,
//                   edge_texels
//   GL stage options: peeler, resolve (scene files and the GL backend only)
#include "peelcd/core/frame.h"
#include "peelcd/gl/options.h"

#include <nlohmann/json.hpp>

namespace peelcd {

nlohmann::json options_to_json(const DetectOptions& options);
nlohmann::json gl_options_to_json(const gl::GlOptions& options);  // peeler, resolve

}  // namespace peelcd
