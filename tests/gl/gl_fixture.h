#pragma once
// One OSMesa context and pipeline per test process, reused by every test (as an application
// would reuse them across frames).
#include "peelcd/core/cpu_peel.h"
#include "peelcd/core/reference.h"
#include "peelcd/gl/pipeline.h"
#include "peelcd/gl_egl/egl_context.h"
#include "peelcd/gl_osmesa/osmesa_context.h"

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

inline std::shared_ptr<gl::Context> test_context() {
  static const std::shared_ptr<gl::Context> context =
      test_backend() == "egl" ? std::shared_ptr<gl::Context>(std::make_shared<gl::EglContext>())
                              : std::shared_ptr<gl::Context>(std::make_shared<gl::OsmesaContext>());
  return context;
}

inline gl::Pipeline& test_pipeline() {  // the pipeline of the backend under test
  static gl::Pipeline pipeline(test_context());
  return pipeline;
}

// Runs `fn` with the test pipeline's peeler set to `peeler`, then sets the default back.
template <class F>
auto with_peeler(Peeler peeler, F&& fn) {
  gl::GlOptions o;
  o.peeler = peeler;
  test_pipeline().set_gl_options(o);
  struct Reset {
    ~Reset() { test_pipeline().set_gl_options(gl::GlOptions{}); }
  } reset;
  return fn();
}

inline Score score(const std::vector<std::uint64_t>& exact, const std::vector<Contact>& reported) {
  return score_contacts(exact, reported);
}

// The point-sampling configuration the pipeline tests were written for (the default before
// conservative mode): DetectOptions with conservative = false, ring IDs, the paper's frame
// (theta = phi = roll = 0) and three fused views.
inline DetectOptions point_sampling() {
  DetectOptions o;
  o.conservative = false;
  o.ids = IdMode::ring;
  o.theta = o.phi = o.roll = 0.0;
  o.views = 3;
  o.stage = Stage::image;  // these tests check the image stage, not the router
  return o;
}

}  // namespace peelcd::test
