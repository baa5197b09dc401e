#pragma once
// The options of a frame as JSON: one writer, used by the result JSON (detect --json), the dump
// metadata (meta.json) and anything else that records a configuration, and its reader. Both
// derive from the option table (peelcd/core/options.h): its recorded rows, their keys, kinds and
// ranges. The scene parser (peelcd/io/scene.h) reads the same keys.
//   GL stage options: peeler, resolve (scene files and the GL backend only)
#include "peelcd/core/frame.h"
#include "peelcd/gl/options.h"

#include <nlohmann/json.hpp>

namespace peelcd {

nlohmann::json options_to_json(const DetectOptions& options);
// The options a JSON object written by options_to_json() records (keys it lacks keep their
// defaults). Throws std::invalid_argument naming an unknown key or a bad value.
DetectOptions options_from_json(const nlohmann::json& json);
nlohmann::json gl_options_to_json(const gl::GlOptions& options);  // peeler, resolve

}  // namespace peelcd
