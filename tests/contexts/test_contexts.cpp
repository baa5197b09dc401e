// The contexts and the backends by name (peelcd/backends.h): what make_gl_context and
// make_image_stage give for each name, and the errors for the names they refuse.
#include "../gl/gl_fixture.h"
#include "peelcd/backends.h"

#include <catch2/catch.hpp>

using namespace peelcd;
using namespace peelcd::test;

TEST_CASE("make_image_stage: cpu is the CPU stage, no GL context", "[contexts]") {
  CHECK(make_gl_context("cpu") == nullptr);
  const std::shared_ptr<ImageStage> stage = make_image_stage("cpu");
  REQUIRE(stage);
  CHECK(dynamic_cast<CpuImageStage*>(stage.get()) != nullptr);
  CHECK(stage->backend() == "cpu");
  CHECK(stage->max_resolution() > 0);
}

TEST_CASE("make_image_stage: an unknown backend is refused by name", "[contexts]") {
  CHECK(make_gl_context("vulkan") == nullptr);
  try {
    make_image_stage("vulkan");
    FAIL("an unknown backend was accepted");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("\"vulkan\"") != std::string::npos);
    CHECK(what.find("osmesa, egl or cpu") != std::string::npos);
  }
#if !PEELCD_HAVE_OSMESA && PEELCD_BUILT_WITH_OSMESA
  CHECK_THROWS_WITH(make_image_stage("osmesa"), Catch::Contains("does not link peelcd::gl_osmesa"));
#elif !PEELCD_HAVE_OSMESA
  CHECK_THROWS_WITH(make_image_stage("osmesa"), Catch::Contains("built without OSMesa"));
#endif
}

TEST_CASE("make_image_stage: egl makes a GL stage whose context reports its platform", "[contexts]") {
  std::shared_ptr<gl::Context> context;
  try {
    context = make_gl_context("egl");
  } catch (const gl::GlError& e) {
    skip_test(std::string("no EGL display here: ") + e.what());
    return;
  }
  REQUIRE(context);
  CHECK(context->backend().rfind("egl", 0) == 0);  // egl-device, egl-surfaceless, ...
  CHECK(!context_renderer(*context).empty());
  const std::shared_ptr<ImageStage> stage = make_image_stage("egl");
  REQUIRE(dynamic_cast<gl::GlImageStage*>(stage.get()) != nullptr);
  CHECK(stage->max_resolution() >= 1024);  // GL 4.3 guarantees GL_MAX_TEXTURE_SIZE >= 16384
  CHECK(stage->backend().rfind("egl", 0) == 0);
}

#if PEELCD_HAVE_OSMESA
TEST_CASE("make_image_stage: osmesa is the software reference (llvmpipe)", "[contexts]") {
  const std::shared_ptr<gl::Context> context = make_gl_context("osmesa");
  REQUIRE(context);
  CHECK(context->backend() == "osmesa");
  CHECK(context_renderer(*context).find("llvmpipe") != std::string::npos);
  CHECK(std::string(kDefaultBackend) == "osmesa");
}
#endif

TEST_CASE("contexts: two contexts made current in turn give each back", "[contexts]") {
  std::shared_ptr<gl::Context> a, b;
  try {
    a = make_gl_context(kDefaultBackend);
    b = make_gl_context("egl");
  } catch (const gl::GlError& e) {
    skip_test(std::string("no second context here: ") + e.what());
    return;
  }
  // Interleaved use, as two pipelines in one program: each makes its own current and gives the
  // previous one back, so each keeps answering as itself.
  const std::string ra = context_renderer(*a);
  const std::string rb = context_renderer(*b);
  CHECK(!ra.empty());
  CHECK(!rb.empty());
  CHECK(context_renderer(*a) == ra);
  CHECK(context_renderer(*b) == rb);
}
