#pragma once
// One OSMesa context and pipeline per test process, reused by every test (as an application
// would reuse them across frames).
#include "core/cpu_peel.h"
#include "core/reference.h"
#include "gl/pipeline.h"
#include "gl_osmesa/osmesa_context.h"

#include <algorithm>
#include <set>

namespace peelcd::test {

inline gl::Pipeline& osmesa_pipeline() {
  static gl::OsmesaContext context;
  static gl::Pipeline pipeline(context);
  return pipeline;
}

inline Score score(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported) {
  return score_contacts(exact, reported);
}

}  // namespace peelcd::test
