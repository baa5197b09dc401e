// A program that links peelcd::core alone (no GL component): the umbrella header compiles, the
// CPU stage starts by name, and the GL backends are refused with what to link.
#include "peelcd/peelcd.h"

#include <catch2/catch.hpp>

using namespace peelcd;

TEST_CASE("peelcd::core alone: make_image_stage(\"cpu\") links and runs a World", "[contexts]") {
  CHECK(std::string(kDefaultBackend) == "cpu");
  const std::shared_ptr<ImageStage> stage = make_image_stage("cpu");
  REQUIRE(stage);
  World world(stage);
  CHECK(world.size() == 0);
  CHECK_THROWS_WITH(make_image_stage("egl"), Catch::Contains("does not link peelcd::gl_egl"));
#if PEELCD_BUILT_WITH_OSMESA
  CHECK_THROWS_WITH(make_image_stage("osmesa"), Catch::Contains("does not link peelcd::gl_osmesa"));
#else
  CHECK_THROWS_WITH(make_image_stage("osmesa"), Catch::Contains("built without OSMesa"));
#endif
}
