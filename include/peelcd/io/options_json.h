#pragma once
// The options of a frame as JSON: one writer, used by the result JSON (detect --json), the dump
// metadata (meta.json) and anything else that records a configuration, and its reader. Both
// derive from the option table (peelcd/core/options.h): its recorded rows, their keys, kinds and
// ranges. The scene parser (peelcd/io/scene.h) reads the same keys.
// The GL stage's settings (peelcd/gl/options.h, gl_option_table()) are written beside them, as
// "gl_options" (a run on a GL stage), never inside "options": goldens recorded with one peeler or
// resolve are compared with runs of the others.
#include "peelcd/core/frame.h"
#include "peelcd/gl/options.h"

#include <nlohmann/json.hpp>

namespace peelcd {

nlohmann::json options_to_json(const DetectOptions& options);
// The options a JSON object written by options_to_json() records (keys it lacks keep their
// defaults). Throws std::invalid_argument naming an unknown key or a bad value.
DetectOptions options_from_json(const nlohmann::json& json);
// Every row of gl_option_table(): {"peeler": "abuffer", "resolve": "auto", "batch": true, ...}.
nlohmann::json gl_options_to_json(const gl::GlOptions& options);
// The GL settings such an object records (keys it lacks keep their defaults). Throws
// std::invalid_argument naming an unknown key or a bad value.
gl::GlOptions gl_options_from_json(const nlohmann::json& json);

}  // namespace peelcd
