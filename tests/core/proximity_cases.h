#pragma once
// Scenes for the proximity checks through a stage (DetectOptions::margin): the geometry classes,
// the depth classes, and near-but-apart pairs (boxes 1e-4 apart, a ball beside a box, two turned
// boxes face to face). Each stage's pairs within the margin are checked against near_pairs()
// (a tree search; tests/core/test_proximity.cpp checks it against CGAL's exact distances).
#include "peelcd/core/image/detector.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/eval/classes.h"

#include <catch2/catch.hpp>

#include <string>
#include <vector>

namespace peelcd::test {

inline std::vector<GeometryClass> proximity_scenes() {
  std::vector<GeometryClass> out = geometry_classes(6);
  for (const DepthClass& d : depth_classes()) out.push_back(d.scene);
  const auto two = [&](std::string name, Mesh a, Mesh b) {
    GeometryClass g;
    g.name = std::move(name);
    g.objects.resize(2);
    g.objects[0].name = "a";
    g.objects[0].mesh = std::move(a);
    g.objects[1].name = "b";
    g.objects[1].mesh = std::move(b);
    out.push_back(std::move(g));
  };
  two("boxes 1e-4 apart", make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), make_box(Vec3(1.0001, 0.2, 0.3), Vec3(2, 0.9, 1.5)));
  two("ball beside a box", make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 16), make_box(Vec3(1.02, -0.3, -0.3), Vec3(2, 0.3, 0.3)));
  Mesh turned = make_box(Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, 0.5));
  const Eigen::AngleAxisd r(0.4, Vec3(1, 2, 3).normalized());
  for (Vec3& v : turned.vertices) v = r * v + Vec3(0.9, 0.1, 0.05);
  two("turned boxes close", make_box(Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, 0.5)), std::move(turned));
  return out;
}

inline double scene_size(const GeometryClass& g) {
  Aabb box;
  for (const Object& o : g.objects) {
    const Aabb b = bounds(o.mesh);
    box.extend(b.lo);
    box.extend(b.hi);
  }
  return box.extent().maxCoeff();
}

// Every pair within `margin` found by `detector` on the scene matches the tree search's, pair
// by pair with the same distances; returns how many pairs were within the margin.
inline std::size_t check_near(Detector& detector, const GeometryClass& g, const DetectOptions& opt) {
  const FrameResult r = detector.detect(g.objects, opt);
  std::size_t within = 0;
  for (std::size_t i = 0; i < g.objects.size(); ++i)
    for (std::size_t j = i + 1; j < g.objects.size(); ++j) {
      const Proximity want = near_pairs(g.objects[i].mesh, g.objects[j].mesh, opt.margin);
      const PairResult* got = nullptr;
      for (const PairResult& p : r.pairs)
        if (p.object_a == i && p.object_b == j) got = &p;
      INFO(g.name << ", objects " << i << " and " << j << ", margin " << opt.margin);
      if (!got) {
        CHECK(want.pairs.empty());
        continue;
      }
      REQUIRE(got->near.pairs.size() == want.pairs.size());
      for (std::size_t k = 0; k < want.pairs.size(); ++k) {
        CHECK(got->near.pairs[k].tri_a == want.pairs[k].tri_a);
        CHECK(got->near.pairs[k].tri_b == want.pairs[k].tri_b);
        CHECK(got->near.pairs[k].distance == want.pairs[k].distance);
      }
      CHECK(got->near.distance == want.distance);
      within += want.pairs.size();
    }
  return within;
}

}  // namespace peelcd::test
