// Proximity through the stages (DetectOptions::margin): the image stage's conservative PCS
// (triangles grown by half the margin) and the exact path's grown boxes miss no pair within the
// margin on the geometry classes, the depth classes and near-but-apart pairs.
#include "../core/proximity_cases.h"
#include "stride.h"  // PEELCD_TEST_STRIDE
#include "peelcd/core/image/cpu_stage.h"

#include <catch2/catch.hpp>

using namespace peelcd;

TEST_CASE("proximity: the image stage's PCS and the exact path miss no pair within the margin", "[proximity]") {
  // The image stage grows every triangle by half the margin (PeelJob::grow): its candidates hold
  // every pair within the margin; the exact path grows the boxes. One view and three (fused).
  Detector d(std::make_shared<CpuImageStage>());
  std::size_t within = 0;
  const std::vector<GeometryClass> scenes = test::proximity_scenes();
  for (std::size_t i = 0; i < scenes.size(); ++i)
    for (const double rel : {1e-3, 2e-2})
      for (const Stage stage : {Stage::image, Stage::exact})
        for (const int views : {1, 3}) {
          if (test::stride_skips(i)) continue;
          const GeometryClass& g = scenes[i];
          DetectOptions opt;
          opt.stage = stage;
          opt.views = views;
          opt.margin = rel * test::scene_size(g);
          within += test::check_near(d, g, opt);
        }
  CHECK(within > 1000 / test::stride());
}
