#pragma once
// The JSON report of `peelcd detect --json`.
#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/gl/options.h"

#include <nlohmann/json.hpp>

namespace peelcd {

// The result's JSON schema name (docs/json.md, docs/schema/result.schema.json).
inline constexpr const char* kResultSchema = "peelcd.result/2";

// The report of one frame. With `check` (one Score per pair, `detect --check`), each pair and
// the frame also carry the comparison with the exact reference.
// `gl`: the GL stage's settings of the run (recorded as "gl_options"; null on the CPU stage).
nlohmann::json to_json(const FrameResult& result, const std::vector<Object>& objects,
                       const DetectOptions& options, const std::vector<Score>* check = nullptr,
                       const gl::GlOptions* gl = nullptr);

}  // namespace peelcd
