// The image stages side by side, and the GL stage's contract with its context: shared
// ownership, the caller's current context given back.
#include "gl_fixture.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/primitives.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

#if PEELCD_HAVE_OSMESA
#include <GL/osmesa.h>
#endif

using namespace peelcd;
using namespace peelcd::test;

TEST_CASE("the CPU image stage gives the GL stage's PCS on the default scene, view by view", "[stages]") {
  const std::vector<Object> scene =
      load_objects(load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json"));
  Detector cpu(std::make_shared<CpuImageStage>());
  std::vector<CapturedView> gl_views, cpu_views;
  DetectOptions opt;  // the default configuration
  opt.stage = Stage::image;  // the image stage is what this checks
  test_pipeline().capture_layers(&gl_views);
  const FrameResult g = test_pipeline().detect(scene, opt);
  test_pipeline().capture_layers(nullptr);
  cpu.capture_layers(&cpu_views);
  const FrameResult c = cpu.detect(scene, opt);
  REQUIRE(g.pairs.size() == 1);
  REQUIRE(c.pairs.size() == 1);
  CHECK(c.pairs[0].resolution == g.pairs[0].resolution);
  CHECK(c.pairs[0].pcs == g.pairs[0].pcs);
  CHECK(c.pairs[0].candidates == g.pairs[0].candidates);
  CHECK(c.pairs[0].colliding.size() == g.pairs[0].colliding.size());
  CHECK(c.pairs[0].colliding.size() == 228);  // every exact pair (the exact reference's count)
  REQUIRE(cpu_views.size() == gl_views.size());
  for (std::size_t v = 0; v < cpu_views.size(); ++v) {
    INFO("view " << v);
    CHECK(cpu_views[v].pcs == gl_views[v].pcs);
    CHECK(cpu_views[v].layers.size() == gl_views[v].layers.size());
  }
  // The layers themselves: the same fragments in nearly every texel (a texel centre within
  // rounding of an edge may go to the other triangle of a shared edge); measured, not assumed.
  std::size_t texels = 0, same = 0;
  for (std::size_t v = 0; v < cpu_views.size(); ++v)
    for (std::size_t k = 0; k < std::min(cpu_views[v].layers.size(), gl_views[v].layers.size()); ++k)
      for (std::size_t i = 0; i + 3 < gl_views[v].layers[k].size(); i += 4) {
        if (gl_views[v].layers[k][i + 1] == 0 && cpu_views[v].layers[k][i + 1] == 0) continue;
        ++texels;
        same += gl_views[v].layers[k][i + 1] == cpu_views[v].layers[k][i + 1];
      }
  INFO(same << " of " << texels << " non-empty layer texels hold the same object and ID");
  CHECK(double(same) >= 0.999 * double(texels));
}

namespace {

// A context that forwards to the test context and counts what the stage asks of it.
struct CountingContext final : gl::Context {
  std::shared_ptr<gl::Context> inner = test_context();
  int current = 0, restored = 0;
  void make_current() override {
    ++current;
    inner->make_current();
  }
  void restore_previous() noexcept override {
    ++restored;
    inner->restore_previous();
  }
  gl::ProcAddress proc_address(const char* name) override { return inner->proc_address(name); }
  std::string backend() const override { return inner->backend(); }
};

}  // namespace

TEST_CASE("the GL stage shares ownership of its context and gives the caller's context back", "[stages]") {
  auto counting = std::make_shared<CountingContext>();
  std::weak_ptr<CountingContext> alive = counting;
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const Mesh b = make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 12, 24);
  const std::vector<Object> objects = {{"a", a, {}, {}}, {"b", b, {}, {}}};
  {
    gl::Pipeline pipeline(counting);
    CHECK(counting->current == counting->restored);  // construction gave the context back
    CountingContext* raw = counting.get();
    counting.reset();  // the caller lets go: the pipeline keeps the context alive
    REQUIRE_FALSE(alive.expired());
    DetectOptions opt;
    opt.stage = Stage::image;  // the image stage is what this checks
    opt.resolution = 64;
    const FrameResult r = pipeline.detect(objects, opt);
    CHECK_FALSE(r.pairs.at(0).colliding.empty());
    CHECK(raw->current == raw->restored);  // every frame gives the context back
    opt.resolution = -1;  // refused before any GL work
    CHECK_THROWS_AS(pipeline.detect(objects, opt), std::invalid_argument);
    CHECK(raw->current == raw->restored);
  }
  CHECK(alive.expired());  // released with the pipeline
}

#if PEELCD_HAVE_OSMESA
TEST_CASE("an OSMesa context the caller had current is current again after a frame", "[stages]") {
  if (test_backend() != "osmesa") {  // the raw OSMesa context is the osmesa run's concern
    skip_test("needs the osmesa run (PEELCD_TEST_BACKEND=" + test_backend() + ")");
    return;
  }
  const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
  OSMesaContext mine = OSMesaCreateContextAttribs(attribs, nullptr);
  REQUIRE(mine);
  std::vector<unsigned char> buffer(16 * 16 * 4);
  REQUIRE(OSMesaMakeCurrent(mine, buffer.data(), GL_UNSIGNED_BYTE, 16, 16));
  const std::vector<Object> objects = {{"a", make_uv_sphere(Vec3(0, 0, 0), 1.0, 8, 16), {}, {}},
                                       {"b", make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 8, 16), {}, {}}};
  DetectOptions opt;
  opt.stage = Stage::image;  // the image stage is what this checks
  opt.resolution = 32;
  test_pipeline().detect(objects, opt);
  CHECK(OSMesaGetCurrentContext() == mine);
  GLint w = 0, h = 0, format = 0;
  void* buf = nullptr;
  REQUIRE(OSMesaGetColorBuffer(mine, &w, &h, &format, &buf));
  CHECK(buf == buffer.data());
  CHECK(w == 16);
  OSMesaDestroyContext(mine);
}
#endif
