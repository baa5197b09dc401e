// A coarse accuracy sweep of the default scene (the long sweeps are commands, see
// docs/accuracy.md): the relations that must hold, and the documented bounds of the default.
#include "peelcd/eval/sweep.h"
#include "gl_fixture.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

#include <cstdio>

using namespace peelcd;
using namespace peelcd::test;

namespace {

SweepConfig config(int res, IdMode ids, PeelMode peel, double slope, int views = 1, bool conservative = false) {
  SweepConfig c;
  c.conservative = conservative;
  c.views = views;
  c.resolution = res;
  c.ids = ids;
  c.peel = peel;
  c.slope = slope;
  return c;
}

}  // namespace

TEST_CASE("coarse sweep of bunny vs dragon: relations and bounds", "[sweep]") {
  const std::vector<Object> objects =
      load_objects(load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json"));
  const DetectOptions point = point_sampling();  // the point-sampling default of 0.2.0
  const DetectOptions defaults;
  REQUIRE(defaults.conservative);
  const std::vector<SweepConfig> configs = {
      config(128, IdMode::unique, PeelMode::alternate, 0.0),  // 0: the paper, unique IDs
      config(128, IdMode::paper, PeelMode::alternate, 0.0),   // 1: the paper, its IDs
      config(256, IdMode::paper, PeelMode::alternate, 0.0),   // 2: the paper at 256^2
      config(256, IdMode::paper, PeelMode::full, 1.0),        // 3: full peeling, paper IDs
      config(128, point.ids, point.peel, point.slope, point.views),  // 4: point sampling, 3 views, 128^2
      config(256, point.ids, point.peel, point.slope, point.views),  // 5: the same at 256^2
      config(16, defaults.ids, defaults.peel, defaults.slope, defaults.views, true),   // 6: conservative, 16^2
      config(128, defaults.ids, defaults.peel, defaults.slope, defaults.views, true),  // 7: the default, 128^2
  };
  const auto directions = sweep_directions(90, 60);  // 10 views, poles included
  REQUIRE(directions.size() == 10);
  const auto rows = run_sweep(test_pipeline().detector(), objects, configs, directions);
  REQUIRE(rows.size() == configs.size() * directions.size());

  std::vector<SweepSummary> s;
  for (std::size_t c = 0; c < configs.size(); ++c) {
    s.push_back(summarize(rows, c));
    std::printf("coarse sweep %-32s avg %6.2f%% max %6.2f%% false %zu\n", configs[c].label().c_str(),
                100 * s[c].avg_miss, 100 * s[c].max_miss, s[c].false_contacts);
  }
  for (const SweepRow& r : rows) {
    INFO(configs[r.config].label() << " theta " << r.theta << " phi " << r.phi);
    CHECK(r.false_contacts == 0);
    CHECK(r.exact == 228);
  }
  // The paper's relations: its IDs beat unique IDs, a larger tile beats a smaller one.
  CHECK(s[1].avg_miss < s[0].avg_miss);
  CHECK(s[2].avg_miss < s[1].avg_miss);
  // Full peeling with the slope epsilon beats the paper's mode at the same tile and IDs.
  CHECK(s[3].avg_miss < s[2].avg_miss);
  // Point sampling's documented bounds on this scene (docs/accuracy.md): 256^2 average <= 0.5%
  // and maximum <= 2%; 128^2 average <= 2%.
  CHECK(s[5].avg_miss <= 0.005);
  CHECK(s[5].max_miss <= 0.02);
  CHECK(s[4].avg_miss <= 0.02);
  // Conservative mode (the default) misses nothing in any direction, down to 16^2 tiles.
  CHECK(s[6].max_miss == 0.0);
  CHECK(s[7].max_miss == 0.0);
}
