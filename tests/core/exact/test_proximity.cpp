// Proximity (peelcd/core/exact/proximity.h, DetectOptions::margin): triangle distances against CGAL's
// exact distances, every pair within the margin against a brute-force exact reference (two
// objects, one object's self pairs), the same through the frame API on both paths and the World
// (tests/eval/test_proximity_classes.cpp: the stages' candidates on every class).
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/world/world.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <catch2/catch.hpp>

#include <algorithm>

#include <random>

using namespace peelcd;

namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;

EK::Point_3 ep(const Vec3& v) { return EK::Point_3(v.x(), v.y(), v.z()); }

// The exact distance of two triangles: 0 when they meet, else the least corner-to-triangle and
// edge-to-edge distance (exact rational arithmetic, one square root in double at the end).
double exact_distance(const TriangleCorners& a, const TriangleCorners& b) {
  const EK::Triangle_3 ta(ep(a[0]), ep(a[1]), ep(a[2])), tb(ep(b[0]), ep(b[1]), ep(b[2]));
  if (!ta.is_degenerate() && !tb.is_degenerate() && CGAL::do_intersect(ta, tb)) return 0.0;
  EK::FT best = -1;
  const auto take = [&](const EK::FT& d) {
    if (best < 0 || d < best) best = d;
  };
  for (int k = 0; k < 3; ++k) {
    take(CGAL::squared_distance(ep(a[k]), tb));
    take(CGAL::squared_distance(ep(b[k]), ta));
    for (int j = 0; j < 3; ++j)
      take(CGAL::squared_distance(EK::Segment_3(ep(a[k]), ep(a[(k + 1) % 3])), EK::Segment_3(ep(b[j]), ep(b[(j + 1) % 3]))));
  }
  return std::sqrt(CGAL::to_double(best));
}

// Triangles whose boxes are farther apart than `margin` along an axis (a gap the distance cannot
// undercut; 1e-9 relative spared for the subtraction's rounding): the brute-force references skip
// their exact distance, which is all their cost.
bool boxes_apart(const TriangleCorners& a, const TriangleCorners& b, double margin) {
  for (int i = 0; i < 3; ++i) {
    const double alo = std::min({a[0][i], a[1][i], a[2][i]}), ahi = std::max({a[0][i], a[1][i], a[2][i]});
    const double blo = std::min({b[0][i], b[1][i], b[2][i]}), bhi = std::max({b[0][i], b[1][i], b[2][i]});
    const double gap = std::max(blo - ahi, alo - bhi);
    if (gap > margin * (1.0 + 1e-9) + 1e-300) return true;
  }
  return false;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> brute(const Mesh& a, const Mesh& b, double margin) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t x = 0; x < a.triangles.size(); ++x)
    for (std::uint32_t y = 0; y < b.triangles.size(); ++y)
      if (!boxes_apart(corners(a, x), corners(b, y), margin) && exact_distance(corners(a, x), corners(b, y)) <= margin)
        out.emplace_back(x, y);
  return out;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> listed(const Proximity& p) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (const NearPair& n : p.pairs) out.emplace_back(n.tri_a, n.tri_b);
  return out;
}


}  // namespace

TEST_CASE("proximity: triangle distances equal the exact ones (relative 1e-9), closest points on the triangles", "[proximity]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int apart = 0;
  for (int k = 0; k < 400; ++k) {
    TriangleCorners a, b;
    const Vec3 shift(u(rng) * 2, u(rng) * 2, u(rng) * 2);
    for (int i = 0; i < 3; ++i) {
      a[i] = Vec3(u(rng), u(rng), u(rng));
      b[i] = Vec3(u(rng), u(rng), u(rng)) + shift;
    }
    Vec3 p, q;
    const double d = triangle_distance(a, b, p, q);
    const double e = exact_distance(a, b);
    INFO(k);
    CHECK(d == Approx(e).epsilon(1e-9).margin(1e-15));
    CHECK((p - q).norm() == Approx(d).epsilon(1e-9).margin(1e-15));
    Vec3 x, y;
    CHECK(triangle_distance(a, {p, p, p}, x, y) < 1e-12);  // p lies on a
    CHECK(triangle_distance(b, {q, q, q}, x, y) < 1e-12);  // q lies on b
    apart += e > 0;
  }
  CHECK(apart > 100);
}

TEST_CASE("proximity: boxes 1e-4 apart, every pair within the margin and the least distance", "[proximity]") {
  const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = make_box(Vec3(1.0001, 0.2, 0.3), Vec3(2, 0.9, 1.5));
  for (const double margin : {5e-5, 1e-4, 1e-3, 0.3}) {
    INFO(margin);
    const Proximity p = near_pairs(a, b, margin);
    CHECK(listed(p) == brute(a, b, margin));
    if (margin >= 1e-4) {
      REQUIRE(p.within());
      CHECK(p.distance == Approx(1e-4).epsilon(1e-9));
      CHECK((p.q - p.p).norm() == Approx(1e-4).epsilon(1e-9));
    } else {
      CHECK_FALSE(p.within());
    }
  }
}

TEST_CASE("proximity: one object's pairs within the margin, none sharing a vertex", "[proximity]") {
  const Mesh m = make_folded_sheet(10, 0.3, 0.12);
  std::vector<std::uint32_t> rep;
  vertex_representatives(m, SelfAdjacency::index, rep);
  const double margin = 0.05;
  const Proximity p = near_self_pairs(m, rep, margin);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> want;
  for (std::uint32_t x = 0; x < m.triangles.size(); ++x)
    for (std::uint32_t y = x + 1; y < m.triangles.size(); ++y)
      if (!triangles_adjacent(m, rep, x, y) && !boxes_apart(corners(m, x), corners(m, y), margin) &&
          exact_distance(corners(m, x), corners(m, y)) <= margin)
        want.emplace_back(x, y);
  CHECK(listed(p) == want);
  CHECK_FALSE(want.empty());
}

TEST_CASE("proximity: objects within the margin are a pair of the frame, on both paths and in the World", "[proximity]") {
  const std::vector<Object> objects = {named_object("a", make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 16)),
                                       named_object("b", make_box(Vec3(1.02, -0.3, -0.3), Vec3(2, 0.3, 0.3)))};
  const double margin = 0.05;
  const auto want = brute(objects[0].mesh, objects[1].mesh, margin);
  REQUIRE_FALSE(want.empty());
  Detector d(std::make_shared<CpuImageStage>());
  for (const Stage stage : {Stage::automatic, Stage::image, Stage::exact}) {
    DetectOptions opt;
    opt.stage = stage;
    opt.margin = margin;
    const FrameResult r = d.detect(objects, opt);
    REQUIRE(r.pairs.size() == 1);
    CHECK(r.pairs[0].colliding.empty());
    CHECK(listed(r.pairs[0].near) == want);
    CHECK(r.pairs[0].near.distance == Approx(0.02).epsilon(0.05));
    // Without the margin the boxes do not overlap: no pair.
    opt.margin = 0.0;
    CHECK(d.detect(objects, opt).pairs.empty());
  }
  World w;
  for (const Object& o : objects) w.add_deforming(o.mesh, o.name);
  DetectOptions opt;
  opt.margin = margin;
  const FrameResult& r = w.collide(opt);
  REQUIRE(r.pairs.size() == 1);
  CHECK(listed(r.pairs[0].near) == want);
}
