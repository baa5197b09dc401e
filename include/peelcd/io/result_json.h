#pragma once
// The JSON report of `peelcd detect --json`.
#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"

#include <nlohmann/json.hpp>

namespace peelcd {

nlohmann::json to_json(const FrameResult& result, const std::vector<Object>& objects,
                       const DetectOptions& options);

}  // namespace peelcd
