#pragma once
// One OSMesa context and pipeline per test process, reused by every test (as an application
// would reuse them across frames).
#include "peelcd/core/image/cpu_peel.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/gl/pipeline.h"
#include "peelcd/gl_egl/egl_context.h"
#include "peelcd/backends.h"

#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>

#include <algorithm>
#include <set>

namespace peelcd::test {

// Marks the running test case as skipped: ctest matches "PEELCD_SKIP:" (SKIP_REGULAR_EXPRESSION
// in tests/CMakeLists.txt) and reports a skip with this reason instead of a pass.
inline void skip_test(const std::string& why) { std::cout << "PEELCD_SKIP: " << why << std::endl; }

// The GL driver stack the GL tests run on: PEELCD_TEST_BACKEND=osmesa (default), egl,
// egl-llvmpipe or egl-zink (tests/main.cpp sets Mesa's environment for the last two). ctest runs
// the suite once per stack; the test bodies are the same.
inline std::string test_stack() {
  const char* b = std::getenv("PEELCD_TEST_BACKEND");
  return b ? b : "osmesa";
}
// The backend of that stack: osmesa or egl.
inline std::string test_backend() { return test_stack() == "osmesa" ? "osmesa" : "egl"; }

// GL_RENDERER of a context.
inline std::string context_renderer(gl::Context& c) {
  c.make_current();
  using GetString = const unsigned char* (*)(unsigned);
  const auto get = reinterpret_cast<GetString>(c.proc_address("glGetString"));
  const unsigned char* r = get ? get(0x1F01 /* GL_RENDERER */) : nullptr;
  const std::string renderer = r ? reinterpret_cast<const char*>(r) : "";
  c.restore_previous();
  return renderer;
}

inline std::shared_ptr<gl::Context> test_context() {
  static const std::shared_ptr<gl::Context> context = [] {
    auto c = make_gl_context(test_backend());  // peelcd/backends.h
    if (!c) {
      skip_test("PEELCD_TEST_BACKEND=" + test_stack() + ": this build has no such backend");
      std::exit(0);
    }
    // A named stack that did not come up as named: the whole test case is a skip, not a pass.
    const std::string stack = test_stack(), renderer = context_renderer(*c);
    const std::string want = stack == "egl-zink" ? "zink" : stack == "egl-llvmpipe" ? "llvmpipe" : "";
    if (!want.empty() && renderer.find(want) == std::string::npos) {
      skip_test("PEELCD_TEST_BACKEND=" + stack + " gave the renderer \"" + renderer + "\"");
      std::exit(0);
    }
    return c;
  }();
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
