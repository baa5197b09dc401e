// OSMesa and EGL in one process (docs/design.md section 6): the pipeline calls GL only through
// pointers resolved from the current context, so both run side by side. On llvmpipe both must
// give bit-identical results: the same PCS and the same contacts.
#include "../gl/gl_fixture.h"
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
