// The frame's planning (peelcd/core/image/planner.h): the stage router shared by the frame API and the
// World, the fused views, the tiles ROIs share the budget by.
#include "peelcd/core/image/planner.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace peelcd;

TEST_CASE("the router takes the cheaper path by the two models, a tie to the exact path", "[planner]") {
  DetectOptions o;
  o.stage = Stage::automatic;
  o.views = 1;
  const StageCost exact{0.0, 0.2, 0.0, 0.05};  // 0.2 us per triangle, 0.05 us per scanned one
  const StageCost image{1.0, 0.01, 2.0, 0.0};  // 1 ms a view, 0.01 us per triangle, 2 ns per texel
  // 1000 triangles, 64^2 tile: exact 0.2 ms, image 1 + 0.01 + 0.008192 ms.
  Route r = route_pair(o, exact, image, 4000.0, 1000.0, 64);
  CHECK(r.exact);
  CHECK(r.predicted_exact_ms == Approx(0.2 + 0.2));  // the scan is in both predictions
  CHECK(r.predicted_image_ms == Approx(0.2 + 1.0 + 0.01 + 0.008192));
  // 100,000 triangles: exact 20 ms, image about 2 ms.
  r = route_pair(o, exact, image, 4000.0, 1e5, 64);
  CHECK_FALSE(r.exact);
  // Each view is paid again.
  o.views = 3;
  const Route three = route_pair(o, exact, image, 0.0, 1e5, 64);
  CHECK(three.predicted_image_ms == Approx(3.0 * image.predict_ms(1e5, 64.0 * 64.0)));
  // A tie: the exact path.
  const StageCost same{0.0, 1.0, 0.0, 0.0};
  o.views = 1;
  CHECK(route_pair(o, same, same, 0.0, 10.0, 64).exact);
}

TEST_CASE("a forced stage decides alone, without predictions", "[planner]") {
  DetectOptions o;
  const StageCost exact{0.0, 1e9, 0.0, 0.0}, image{0.0, 1e9, 0.0, 0.0};
  o.stage = Stage::exact;
  Route r = route_pair(o, exact, image, 10.0, 10.0, 64);
  CHECK(r.exact);
  CHECK(r.predicted_exact_ms == 0.0);
  o.stage = Stage::image;
  r = route_pair(o, exact, image, 10.0, 10.0, 64);
  CHECK_FALSE(r.exact);
  CHECK(r.predicted_image_ms == 0.0);
}

TEST_CASE("the World's exact model is per candidate couple, with no scan", "[planner]") {
  const StageCost w = world_exact_cost();
  CHECK(w.view_ms == 0.0);
  CHECK(w.scan_us == 0.0);
  CHECK(w.predict_ms(1000.0, 0.0) == Approx(kWorldCandidateUs));
  // The frame API's built-in model charges a scan (culling reads both meshes).
  CHECK(exact_path_cost().scan_us > 0.0);
}

TEST_CASE("tiles by need are granted when they fit, else scaled down together", "[planner]") {
  std::vector<int> tiles;
  allocate_tiles(512, {128, 256}, tiles);  // 128^2 + 256^2 < 512^2: granted
  CHECK(tiles == std::vector<int>{128, 256});
  allocate_tiles(256, {256, 256, 256}, tiles);  // 3 x 256^2 > 256^2: scaled by 1/sqrt(3), to 16s
  REQUIRE(tiles.size() == 3);
  double area = 0.0;
  for (const int t : tiles) {
    CHECK(t % 16 == 0);
    CHECK(t >= 16);
    CHECK(t <= 256);
    area += double(t) * t;
  }
  CHECK(area <= 256.0 * 256.0);
  allocate_tiles(64, {}, tiles);
  CHECK(tiles.empty());
}

TEST_CASE("the texture budget is split among ROIs in power-of-two tiles", "[planner]") {
  CHECK(tile_resolution(512, 1) == 512);
  CHECK(tile_resolution(512, 2) == 256);
  CHECK(tile_resolution(512, 4) == 256);
  CHECK(tile_resolution(512, 5) == 128);
  CHECK(tile_resolution(512, 16) == 128);
  CHECK(tile_resolution(512, 17) == 64);
  CHECK(tile_resolution(512, 100000) == 16);  // floor: a tile smaller than 16^2 samples nothing useful
  CHECK_THROWS_AS(tile_resolution(0, 1), std::invalid_argument);
}

TEST_CASE("a ROI's tile is capped at edge_texels texels per median edge across the region", "[planner]") {
  const Aabb region{Vec3(0, 0, 0), Vec3(2, 1, 0.5)};  // longest side 2
  CHECK(edge_tile_resolution(512, region, 0.25, 12) == 96);   // 12 * 2 / 0.25 = 96
  CHECK(edge_tile_resolution(512, region, 0.3, 12) == 80);    // 80 (ceil 80), a multiple of 16
  CHECK(edge_tile_resolution(512, region, 0.29, 12) == 96);   // 82.8 -> 83 -> 96
  CHECK(edge_tile_resolution(512, region, 10.0, 12) == 16);   // never below 16
  CHECK(edge_tile_resolution(64, region, 0.01, 12) == 64);    // never above the budget's share
  CHECK(edge_tile_resolution(40, region, 0.25, 12) == 40);    // a share that is not a multiple of 16 stays
  CHECK(edge_tile_resolution(512, region, 0.25, 0) == 512);   // 0: always the share
  CHECK(edge_tile_resolution(512, region, 0.0, 12) == 512);   // no edge to go by
  CHECK(edge_tile_resolution(512, Aabb{}, 0.25, 12) == 512);  // empty region
  const Aabb flat{Vec3(0, 0, 0), Vec3(0, 0, 0)};               // boxes touching at a point
  CHECK(edge_tile_resolution(512, flat, 0.25, 12) == 16);
}

TEST_CASE("a NaN median edge gives the budget's share", "[planner][nonfinite]") {
  const Aabb region{Vec3(0, 0, 0), Vec3(2, 1, 0.5)};
  CHECK(edge_tile_resolution(512, region, std::nan(""), 12) == 512);
}
