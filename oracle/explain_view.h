#pragma once
// One captured view of explain's trace (explain_view.cpp; private to the oracle component): where
// the two triangles land, each texel's layers analysed, the view summarised and cropped.
#include "peelcd/oracle/explain.h"

#include <set>
#include <vector>

namespace peelcd::oracle::detail {

// Step 3: one captured view of the pair's ROI.
ViewReport trace_view(const Explanation& e, const CapturedView& cv, const Object& oa, const Object& ob,
                      const DetectOptions& opt, const std::vector<std::uint32_t>& kept_a,
                      const std::vector<std::uint32_t>& kept_b, const std::set<std::uint32_t>& stand_a,
                      const std::set<std::uint32_t>& stand_b, const TriangleCorners& ca, const TriangleCorners& cb);

}  // namespace peelcd::oracle::detail
