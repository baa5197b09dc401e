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

