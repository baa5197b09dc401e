// The GPU resolve's certified filter (peelcd/core/image/certified_apart.inc), run in C++ on the
// float corners a GPU would hold: whenever it says two triangles are apart, the exact test on
// the true (double) triangles says they do not intersect, and with a margin, their distance
// exceeds it. The cases are the narrow phase's adversarial families (touching, coplanar,
// near-coplanar, slivers, at scales 1e-6 .. 1e6 and offsets up to 1e6), each moved by a random
// pose into a ROI's local frame as gl/batch.cpp does: a rigid object's corners transformed in
// float by the rounded pose, a deforming object's rounded from their ROI-local doubles.
#include "../adversarial.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/image/certified_apart.h"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include <cstdio>
#include <cstdlib>
#include <random>

using namespace peelcd;
using namespace peelcd::test;

namespace {

struct GpuTriangle {
  certified::vec3 c[3];
  float error = 0.0f;  // the largest corner error bound
};

// A rigid object's corner as the resolve computes it: fl(M fl(x) + t) with M, t the pose (minus
// the ROI centre) rounded to float, summed in the order the shader's mat4 product might.
GpuTriangle rigid_corners(const TriangleCorners& local, const Eigen::Affine3d& roi_from_object) {
  const Eigen::Matrix4d m = roi_from_object.matrix();
  float mf[3][4];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) mf[i][j] = float(m(i, j));
  GpuTriangle t;
  for (int k = 0; k < 3; ++k) {
    const float x[3] = {float(local[k].x()), float(local[k].y()), float(local[k].z())};
    float p[3], mag[3];
    for (int i = 0; i < 3; ++i) {
      p[i] = ((mf[i][0] * x[0] + mf[i][1] * x[1]) + mf[i][2] * x[2]) + mf[i][3];
      mag[i] = std::fabs(mf[i][0]) * std::fabs(x[0]) + std::fabs(mf[i][1]) * std::fabs(x[1]) +
               std::fabs(mf[i][2]) * std::fabs(x[2]) + std::fabs(mf[i][3]);
    }
    t.c[k] = {p[0], p[1], p[2]};
    t.error = std::max(t.error, certified::certified_corner_error(std::max({mag[0], mag[1], mag[2]})));
  }
  return t;
}

// A deforming object's corner: its ROI-local double rounded to float (the pose is the identity).
GpuTriangle frame_corners(const TriangleCorners& roi_local) {
  GpuTriangle t;
  for (int k = 0; k < 3; ++k) {
    t.c[k] = {float(roi_local[k].x()), float(roi_local[k].y()), float(roi_local[k].z())};
    const float mag = std::max({std::fabs(t.c[k].x), std::fabs(t.c[k].y), std::fabs(t.c[k].z)});
    t.error = std::max(t.error, certified::certified_corner_error(mag));
  }
  return t;
}

bool apart(const GpuTriangle& a, const GpuTriangle& b, float reach) {
  return certified::certified_apart(a.c[0], a.c[1], a.c[2], a.error, b.c[0], b.c[1], b.c[2], b.error, reach);
}

TriangleCorners moved(const TriangleCorners& t, const Eigen::Affine3d& m) { return {m * t[0], m * t[1], m * t[2]}; }

struct Tally {
  std::size_t cases = 0, intersecting = 0, disjoint = 0, dropped = 0, wrong = 0;
  std::size_t near_cases = 0, near_dropped = 0, near_wrong = 0;
  std::size_t resolvable = 0, resolvable_dropped = 0;  // generic family, scale >= 1, offset <= 1e3
};

}  // namespace

TEST_CASE("the GPU's certified filter drops only triangles that are truly apart", "[certified][adversarial]") {
  const char* env = std::getenv("PEELCD_ADVERSARIAL_CASES");
  const std::size_t n = env ? std::strtoull(env, nullptr, 10) : 100000;
  AdversarialGenerator gen(20261128);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Tally t;
  for (std::size_t i = 0; i < n; ++i) {
    const AdversarialCase c = gen.next();
    // Two poses (A's and B's object frames to the world), then the ROI centre: near the contact,
    // or the world origin (large ROI-local coordinates).
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
    pose.translation() = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * (i % 3 == 0 ? 1e3 : 1.0);
    const TriangleCorners wa = moved(c.a, pose), wb = moved(c.b, pose);  // the truth, in doubles
    const Vec3 centre = i % 4 == 0 ? Vec3::Zero() : Vec3(wa[0]);
    // Shape-local corners: the world corners in a second, random frame of each object.
    Eigen::Affine3d to_a = Eigen::Affine3d::Identity(), to_b = Eigen::Affine3d::Identity();
    to_a.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
    to_a.translation() = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    to_b.linear() = Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized().toRotationMatrix();
    const TriangleCorners la = moved(wa, to_a.inverse()), lb = moved(wb, to_b.inverse());
    // The truth the host tests: the shape-local doubles moved by the poses (as the detector does).
    Eigen::Affine3d roi = Eigen::Affine3d::Identity();
    roi.translation() = -centre;
    const TriangleCorners ta = moved(la, roi * to_a), tb = moved(lb, roi * to_b);
    const bool meet = triangles_intersect(ta, tb);
    // On the GPU: either corner kind for either triangle.
    const GpuTriangle ga = i % 2 ? rigid_corners(la, roi * to_a) : frame_corners(ta);
    const GpuTriangle gb = (i / 2) % 2 ? rigid_corners(lb, roi * to_b) : frame_corners(tb);
    ++t.cases;
    (meet ? t.intersecting : t.disjoint)++;
    const bool resolvable = c.family == Family::generic && c.scale >= 1.0 && c.offset <= 1e3 && !meet;
    t.resolvable += resolvable;
    if (apart(ga, gb, 0.0f)) {
      ++t.dropped;
      t.resolvable_dropped += resolvable;
      if (meet) {
        ++t.wrong;
        FAIL_CHECK("case " << i << " (" << kFamilyNames[int(c.family)] << ", scale " << c.scale << ", offset "
                           << c.offset << "): dropped, but the triangles intersect");
      }
    }
    // A margin: dropped only beyond it (the distance in double, within 1e-9 of the exact one).
    if (!meet) {
      Vec3 p, q;
      const double d = triangle_distance(ta, tb, p, q);
      const double reach = d * std::uniform_real_distribution<double>(0.5, 1.5)(rng);
      ++t.near_cases;
      if (apart(ga, gb, float(reach))) {
        ++t.near_dropped;
        if (d <= reach * (1.0 + 1e-9) && d > 0.0) {
          ++t.near_wrong;
          FAIL_CHECK("case " << i << " (" << kFamilyNames[int(c.family)] << ", scale " << c.scale << ", offset "
                             << c.offset << ", centre " << centre.transpose() << ", kinds " << i % 2 << (i / 2) % 2
                             << "): dropped at reach " << reach << ", but the distance is " << d
                             << "; errors " << ga.error << " " << gb.error);
        }
      }
    }
  }
  std::printf("certified filter: %zu cases (%zu intersecting, %zu disjoint): %zu dropped, %zu of them intersecting; "
              "with a margin: %zu disjoint cases, %zu dropped, %zu within the margin; generic disjoint pairs float "
              "resolves: %zu of %zu dropped\n",
              t.cases, t.intersecting, t.disjoint, t.dropped, t.wrong, t.near_cases, t.near_dropped, t.near_wrong,
              t.resolvable_dropped, t.resolvable);
  CHECK(t.wrong == 0);
  CHECK(t.near_wrong == 0);
  // The filter must do its work where float resolves the gap: the generic family's disjoint pairs
  // (random triangles in a unit box at scales >= 1, no offset beyond 1e3) are dropped but for a
  // few whose gap is within the widening; and some with a margin. The touching, coplanar and
  // near-coplanar families are a hair apart by construction: kept, as they must be.
  REQUIRE(t.intersecting > 0);
  REQUIRE(t.resolvable > n / 50);
  CHECK(t.resolvable_dropped >= t.resolvable * 99 / 100);
  CHECK(t.near_dropped > 0);
}

TEST_CASE("the certified filter keeps what it cannot bound: NaN, infinities, huge coordinates", "[certified]") {
  const certified::vec3 a0{0, 0, 0}, a1{1, 0, 0}, a2{0, 1, 0};
  const certified::vec3 far0{0, 0, 5}, far1{1, 0, 5}, far2{0, 1, 5};
  CHECK(certified::certified_apart(a0, a1, a2, 1e-6f, far0, far1, far2, 1e-6f, 0.0f));   // 5 apart
  CHECK(certified::certified_apart(a0, a1, a2, 1e-6f, far0, far1, far2, 1e-6f, 4.9f));   // beyond the margin
  CHECK(!certified::certified_apart(a0, a1, a2, 1e-6f, far0, far1, far2, 1e-6f, 5.0f));  // within it
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  CHECK(!certified::certified_apart(a0, a1, a2, 1e-6f, {0, 0, nan}, far1, far2, 1e-6f, 0.0f));
  CHECK(!certified::certified_apart(a0, a1, {0, inf, 0}, 1e-6f, far0, far1, far2, 1e-6f, 0.0f));
  CHECK(!certified::certified_apart(a0, a1, a2, nan, far0, far1, far2, 1e-6f, 0.0f));
  const certified::vec3 h0{2e8f, 0, 5}, h1{2e8f + 16, 0, 5}, h2{2e8f, 16, 5};
  CHECK(!certified::certified_apart(a0, a1, a2, 1e-6f, h0, h1, h2, 1e-6f, 0.0f));  // beyond 1e8: kept
  // Touching (a shared corner) is never apart, whatever the rounding.
  CHECK(!certified::certified_apart(a0, a1, a2, 0.0f, a1, {2, 0, 0}, {1, 0, 1}, 0.0f, 0.0f));
}
