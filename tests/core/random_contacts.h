#pragma once
// Seeded random intersecting triangle pairs as two-object scenes at random poses, view frames
// and resolutions: the property "conservative mode finds every intersecting pair" is checked on
// them (tests/eval/test_conservative_classes.cpp on the CPU stage, tests/gl/test_conservative.cpp on GL).
// The pairs come from the adversarial generator (coplanar, touching, slivers, zero-area, tiny
// and huge scales, far offsets); each object is a world-space triangle or, every other case, a
// rigid shape moved by a random pose (the pose's float error is part of what is tested).
#include "adversarial.h"

#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"

#include <memory>
#include <random>
#include <vector>

namespace peelcd::test {

struct RandomContact {
  std::vector<Object> objects;
  DetectOptions options;
  Family family;
  int index = 0;
};

class RandomContacts {
 public:
  explicit RandomContacts(std::uint64_t seed) : gen_(seed), rng_(seed ^ 0x9e3779b97f4a7c15ull) {}

  // The next case whose two triangles intersect (exact test).
  RandomContact next() {
    for (;;) {
      const AdversarialCase c = gen_.next();
      ++count_;
      Eigen::Affine3d pose = Eigen::Affine3d::Identity();
      if (count_ % 3 == 0) {  // a random rotation about the pair (translation keeps the offset)
        const Vec3 centre = (c.a[0] + c.b[0]) / 2.0;
        pose.translate(centre);
        pose.rotate(Eigen::AngleAxisd(angle(), Vec3(unit(), unit(), unit()).normalized()));
        pose.translate(-centre);
      }
      TriangleCorners a = c.a, b = c.b;
      for (Vec3& p : a) p = pose * p;
      for (Vec3& p : b) p = pose * p;
      if (!a[0].allFinite() || !triangles_intersect(a, b)) continue;
      RandomContact r;
      r.family = c.family;
      r.index = count_;
      r.objects.push_back(object("a", c.a, pose, count_ % 2 == 0));
      r.objects.push_back(object("b", c.b, pose, count_ % 4 == 1));
      // The world meshes must be exactly the ones tested above.
      if (!(r.objects[0].mesh.vertices[0] == a[0] && r.objects[1].mesh.vertices[0] == b[0])) continue;
      DetectOptions& o = r.options;
      o.theta = 360.0 * (unit() + 1.0) / 2.0;
      o.phi = 90.0 * unit();
      o.roll = 180.0 * unit();
      const int res[] = {0, 16, 16, 32, 64, 128, 256};
      o.resolution = res[pick(7)];
      o.cull = pick(2) ? Cull::contact : Cull::box;
      return r;
    }
  }

 private:
  AdversarialGenerator gen_;
  std::mt19937_64 rng_;
  int count_ = 0;
  double unit() { return std::uniform_real_distribution<double>(-1, 1)(rng_); }
  double angle() { return std::uniform_real_distribution<double>(0, 2 * M_PI)(rng_); }
  int pick(int n) { return int(rng_() % std::uint64_t(n)); }

  // A one-triangle object: world corners pose * t; rigid ones keep t as their shape.
  static Object object(const char* name, const TriangleCorners& t, const Eigen::Affine3d& pose, bool rigid) {
    Object o;
    o.name = name;
    Mesh local;
    for (const Vec3& p : t) local.vertices.push_back(p);
    local.triangles.push_back({0, 1, 2});
    o.mesh = local;
    for (Vec3& p : o.mesh.vertices) p = pose * p;
    if (rigid) o.rigid = RigidMotion{std::make_shared<const Mesh>(local), pose};
    return o;
  }
};

}  // namespace peelcd::test
