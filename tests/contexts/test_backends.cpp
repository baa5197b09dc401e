// OSMesa and EGL in one process (docs/design.md section 6): the pipeline calls GL only through
// pointers resolved from the current context, so both run side by side. On llvmpipe both must
// give bit-identical results: the same PCS and the same contacts.
#include "../gl/gl_fixture.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/world/world.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

using namespace peelcd;
using namespace peelcd::test;

TEST_CASE("OSMesa and EGL (llvmpipe) in one process give identical PCS and contacts", "[backends]") {
#if !PEELCD_HAVE_OSMESA
  skip_test("built without OSMesa: the goldens are the reference (golden compare --backend egl)");
  return;
#else
  auto osmesa = std::make_shared<gl::OsmesaContext>();
  gl::Pipeline reference(osmesa);
  auto egl = std::make_shared<gl::EglContext>();
  gl::Pipeline other(egl);
  INFO("EGL platform " << egl->backend() << ", renderer " << other.renderer());
  if (other.renderer().find("llvmpipe") == std::string::npos) {
    skip_test("EGL runs on " + other.renderer() + ", not llvmpipe: bit-identity is not expected");
    return;
  }
  const std::vector<Object> scene = load_objects(load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json"));
  for (const auto& [theta, phi] : std::vector<std::pair<double, double>>{{0, 0}, {45, 30}, {200, -40}}) {
    for (PeelMode peel : {PeelMode::alternate, PeelMode::full}) {
      DetectOptions opt;
      opt.stage = Stage::image;  // the image stage is what this checks
      opt.theta = theta;
      opt.phi = phi;
      opt.resolution = 128;
      opt.peel = peel;
      // Alternate between the contexts frame by frame: each pipeline makes its own current.
      const PairResult a = reference.detect(scene, opt).pairs.at(0);
      const PairResult b = other.detect(scene, opt).pairs.at(0);
      INFO("theta " << theta << " phi " << phi << " " << to_string(peel));
      CHECK(a.layers == b.layers);
      CHECK(a.passes == b.passes);
      CHECK(a.pcs == b.pcs);
      REQUIRE(a.colliding.size() == b.colliding.size());
      for (std::size_t i = 0; i < a.colliding.size(); ++i) {
        CHECK(a.colliding[i].tri_a == b.colliding[i].tri_a);
        CHECK(a.colliding[i].tri_b == b.colliding[i].tri_b);
      }
    }
  }
#endif
}

TEST_CASE("OSMesa and EGL Worlds of different settings used in turn give each one's pairs alone", "[backends]") {
#if !PEELCD_HAVE_OSMESA
  skip_test("built without OSMesa");
  return;
#else
  // Mesa's OSMesa and EGL drivers share one GL dispatch: each stage must reach its own context
  // every frame, whatever the other made current. Different views give the two stages buffers
  // of different sizes (a stage drawing into the other's context fails or reads wrong data).
  const auto sphere = [](double x) {
    return std::make_shared<const Mesh>(make_uv_sphere(Vec3(x, 0.1 * x, 0.05 * x), 1.0, 24, 24));
  };
  const auto a = sphere(0.0), b = sphere(1.2);
  const auto world = [&](const std::string& backend) {
    auto w = std::make_unique<World>(make_image_stage(backend));
    w->add_rigid(a, Eigen::Affine3d::Identity());
    w->add_rigid(b, Eigen::Affine3d::Identity());
    return w;
  };
  for (const auto& [views_egl, views_osmesa] : std::vector<std::pair<int, int>>{{3, 1}, {1, 3}}) {
    DetectOptions egl_opt, osmesa_opt;
    egl_opt.stage = osmesa_opt.stage = Stage::image;
    egl_opt.views = views_egl;
    osmesa_opt.views = views_osmesa;
    // Each alone first, then both in turn, each frame compared with its own.
    const auto pairs_of = [](const FrameResult& f) {
      std::vector<std::pair<std::uint32_t, std::uint32_t>> v;
      for (const PairResult& p : f.pairs)
        for (const Contact& c : p.colliding) v.emplace_back(c.tri_a, c.tri_b);
      return v;
    };
    const auto alone_egl = pairs_of(world("egl")->collide(egl_opt));
    const auto alone_osmesa = pairs_of(world("osmesa")->collide(osmesa_opt));
    REQUIRE(!alone_egl.empty());
    auto e = world("egl"), o = world("osmesa");
    for (int frame = 0; frame < 4; ++frame) {
      INFO("EGL views " << views_egl << ", OSMesa views " << views_osmesa << ", frame " << frame);
      CHECK(pairs_of(e->collide(egl_opt)) == alone_egl);
      CHECK(pairs_of(o->collide(osmesa_opt)) == alone_osmesa);
    }
  }
#endif
}
