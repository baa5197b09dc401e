#pragma once
// One OSMesa context and pipeline per test process, reused by every test (as an application
// would reuse them across frames).
#include "core/cpu_peel.h"
#include "core/reference.h"
#include "gl/pipeline.h"
#include "gl_egl/egl_context.h"
#include "gl_osmesa/osmesa_context.h"

#include <cstdlib>
#include <memory>
#include <string>

#include <algorithm>
#include <set>

namespace peelcd::test {

// The backend the GL tests run on: PEELCD_TEST_BACKEND=osmesa (default) or egl. ctest runs the
// suite once per backend; the test bodies are the same.
inline std::string test_backend() {
  const char* b = std::getenv("PEELCD_TEST_BACKEND");
  return b ? b : "osmesa";
}

inline gl::Context& test_context() {
  static const std::unique_ptr<gl::Context> context =
      test_backend() == "egl" ? std::unique_ptr<gl::Context>(new gl::EglContext())
                              : std::unique_ptr<gl::Context>(new gl::OsmesaContext());
  return *context;
}

inline gl::Pipeline& test_pipeline() {  // the pipeline of the backend under test
  static gl::Pipeline pipeline(test_context());
  return pipeline;
}

inline Score score(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported) {
  return score_contacts(exact, reported);
}

}  // namespace peelcd::test
