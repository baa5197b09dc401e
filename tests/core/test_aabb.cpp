#include "peelcd/core/broad_phase.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/primitives.h"

#include <catch2/catch.hpp>

#include <random>

using namespace peelcd;

TEST_CASE("bounds and intersection of boxes", "[aabb]") {
  const Aabb a = bounds(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)));
  const Aabb b = bounds(make_box(Vec3(0.5, 0.25, -1), Vec3(2, 0.75, 0.5)));
  CHECK(a.lo == Vec3(0, 0, 0));
  CHECK(a.hi == Vec3(1, 1, 1));
  const Aabb roi = intersection(a, b);
  CHECK(roi.lo == Vec3(0.5, 0.25, 0));
  CHECK(roi.hi == Vec3(1, 0.75, 0.5));
  CHECK(a.overlaps(b));
  CHECK_FALSE(roi.empty());

  SECTION("boxes that only touch overlap (a touching contact must reach the GPU)") {
    const Aabb c = bounds(make_box(Vec3(1, 0, 0), Vec3(2, 1, 1)));
    CHECK(a.overlaps(c));
    CHECK_FALSE(intersection(a, c).empty());
    CHECK(intersection(a, c).extent().x() == 0.0);
  }
  SECTION("separated boxes give an empty ROI") {
    const Aabb d = bounds(make_box(Vec3(1.5, 0, 0), Vec3(2, 1, 1)));
    CHECK_FALSE(a.overlaps(d));
    CHECK(intersection(a, d).empty());
  }
}

TEST_CASE("sort-and-sweep finds exactly the overlapping pairs of brute force", "[aabb]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(0, 10), size(0.1, 2);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Aabb> boxes(40);
    for (Aabb& b : boxes) {
      b.lo = Vec3(pos(rng), pos(rng), pos(rng));
      b.hi = b.lo + Vec3(size(rng), size(rng), size(rng));
    }
    std::vector<std::pair<std::size_t, std::size_t>> brute;
    for (std::size_t i = 0; i < boxes.size(); ++i)
      for (std::size_t j = i + 1; j < boxes.size(); ++j)
        if (boxes[i].overlaps(boxes[j])) brute.emplace_back(i, j);
    CHECK(overlapping_pairs(boxes) == brute);
  }
}

TEST_CASE("the texture budget is split among ROIs in power-of-two tiles", "[aabb]") {
  CHECK(tile_resolution(512, 1) == 512);
  CHECK(tile_resolution(512, 2) == 256);
  CHECK(tile_resolution(512, 4) == 256);
  CHECK(tile_resolution(512, 5) == 128);
  CHECK(tile_resolution(512, 16) == 128);
  CHECK(tile_resolution(512, 17) == 64);
  CHECK(tile_resolution(512, 100000) == 16);  // floor: a tile smaller than 16^2 samples nothing useful
  CHECK_THROWS_AS(tile_resolution(0, 1), std::invalid_argument);
}

TEST_CASE("a ROI's tile is capped at edge_texels texels per median edge across the region", "[aabb]") {
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

TEST_CASE("a NaN median edge gives the budget's share", "[aabb][nonfinite]") {
  const Aabb region{Vec3(0, 0, 0), Vec3(2, 1, 0.5)};
  CHECK(edge_tile_resolution(512, region, std::nan(""), 12) == 512);
}
