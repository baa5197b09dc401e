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

TEST_CASE("sort-and-sweep keeps brute force's pairs with touching, equal and empty boxes, in every size", "[aabb]") {
  // Integer corners: many boxes share a lower x or only touch (closed boxes: they overlap);
  // empty boxes (lower above upper on one axis) are in no pair. From a few boxes (the pairs
  // sorted by comparison) to a thousand (by radix over the packed indices).
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> pos(0, 12), size(0, 3), pick(0, 9);
  for (const std::size_t count : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(9), std::size_t(60),
                                  std::size_t(257), std::size_t(1000)}) {
    std::vector<Aabb> boxes(count);
    for (Aabb& b : boxes) {
      const double span = count > 300 ? 3.0 : 1.0;  // more room for more boxes
      b.lo = span * Vec3(pos(rng), pos(rng), pos(rng));
      b.hi = b.lo + Vec3(size(rng), size(rng), size(rng));
      if (pick(rng) == 0) {  // empty on one axis
        const int axis = pick(rng) % 3;
        b.hi[axis] = b.lo[axis] - 1.0;
      }
      if (pick(rng) == 1) b = Aabb{};  // the empty box
    }
    std::vector<std::pair<std::size_t, std::size_t>> brute;
    for (std::size_t i = 0; i < boxes.size(); ++i)
      for (std::size_t j = i + 1; j < boxes.size(); ++j)
        if (!boxes[i].empty() && !boxes[j].empty() && boxes[i].overlaps(boxes[j])) brute.emplace_back(i, j);
    INFO(count << " boxes, " << brute.size() << " pairs");
    CHECK(overlapping_pairs(boxes) == brute);
    // The scratch kept from call to call gives the same pairs.
    std::vector<std::pair<std::size_t, std::size_t>> out;
    SweepScratch scratch;
    overlapping_pairs(boxes, out, scratch);
    overlapping_pairs(boxes, out, scratch);
    CHECK(out == brute);
  }
}
