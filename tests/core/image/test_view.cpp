#include "peelcd/core/image/planner.h"
#include "peelcd/core/image/view.h"

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

using namespace peelcd;
using Catch::Matchers::WithinAbs;

TEST_CASE("view direction follows d = (cos phi cos theta, cos phi sin theta, sin phi)", "[view]") {
  CHECK((view_direction(0, 0) - Vec3(1, 0, 0)).norm() < 1e-15);
  CHECK((view_direction(90, 0) - Vec3(0, 1, 0)).norm() < 1e-15);
  CHECK((view_direction(0, 90) - Vec3(0, 0, 1)).norm() < 1e-15);
  CHECK((view_direction(123, -90) - Vec3(0, 0, -1)).norm() < 1e-15);
}

TEST_CASE("view frames are right-handed and orthonormal for every direction, poles included", "[view]") {
  for (double phi = -90; phi <= 90; phi += 10)
    for (double theta = 0; theta < 360; theta += 30) {
      const ViewFrame f = view_frame(theta, phi);
      INFO("theta " << theta << " phi " << phi);
      CHECK_THAT(f.u.norm(), WithinAbs(1, 1e-12));
      CHECK_THAT(f.v.norm(), WithinAbs(1, 1e-12));
      CHECK_THAT(f.u.dot(f.v), WithinAbs(0, 1e-12));
      CHECK_THAT(f.u.dot(f.d), WithinAbs(0, 1e-12));
      CHECK((f.u.cross(f.v) - f.d).norm() < 1e-12);
    }
}

TEST_CASE("fused views look along d, then u, then v, and two views are the first two of three", "[view]") {
  for (const auto& [theta, phi] : std::vector<std::pair<double, double>>{{0, 0}, {45, 30}, {200, -90}}) {
    DetectOptions o;
    o.theta = theta;
    o.phi = phi;
    const ViewFrame f = view_frame(theta, phi, o.roll);  // the default roll turns u and v about d
    std::vector<std::vector<ViewFrame>> by_count;
    for (int views = 1; views <= 3; ++views) {
      o.views = views;
      by_count.push_back(fused_view_frames(o));
      REQUIRE(by_count.back().size() == std::size_t(views));
    }
    const std::vector<ViewFrame>& three = by_count[2];
    CHECK((three[0].d - f.d).norm() == 0.0);
    CHECK((three[1].d - f.u).norm() == 0.0);
    CHECK((three[2].d - f.v).norm() == 0.0);
    for (const ViewFrame& g : three) CHECK((g.u.cross(g.v) - g.d).norm() < 1e-12);  // right-handed
    for (int views = 1; views <= 2; ++views)
      for (int k = 0; k < views; ++k) {
        CHECK(by_count[views - 1][k].d == three[k].d);
        CHECK(by_count[views - 1][k].u == three[k].u);
      }
  }
  DetectOptions bad;
  for (int views : {0, 4}) {
    bad.views = views;
    CHECK_THROWS_AS(fused_view_frames(bad), std::invalid_argument);
  }
}

TEST_CASE("the ROI view maps every corner of the ROI box into the clip cube", "[view]") {
  Aabb roi;
  roi.lo = Vec3(1e6 - 0.5, -2, 3);
  roi.hi = Vec3(1e6 + 0.25, -1, 3.5);
  for (double phi : {-90.0, -35.0, 0.0, 20.0, 90.0})
    for (double theta : {0.0, 45.0, 200.0}) {
      const RoiView v = make_roi_view(roi, view_frame(theta, phi), 256, 0.0);
      const auto m = v.clip_from_local();
      double max_xy = 0, max_z = 0;
      for (int c = 0; c < 8; ++c) {
        const Vec3 p((c & 1 ? roi.hi : roi.lo).x(), (c & 2 ? roi.hi : roi.lo).y(), (c & 4 ? roi.hi : roi.lo).z());
        const Vec3 local = p - v.center;  // double: the far-from-origin offset is removed here
        double clip[3];
        for (int r = 0; r < 3; ++r) clip[r] = m[r] * local.x() + m[4 + r] * local.y() + m[8 + r] * local.z();
        max_xy = std::max({max_xy, std::abs(clip[0]), std::abs(clip[1])});
        max_z = std::max(max_z, std::abs(clip[2]));
      }
      INFO("theta " << theta << " phi " << phi);
      CHECK(max_xy <= 1.0 + 1e-6);
      CHECK_THAT(max_z, WithinAbs(1.0, 1e-6));   // the depth range is exactly the box's
      CHECK_THAT(max_xy, WithinAbs(1.0, 1e-6));  // and the square image is as tight as it can be
      CHECK(v.texel() == Approx(2 * v.half_uv / 256));
    }
}

TEST_CASE("a ROI without extent needs a margin", "[view]") {
  Aabb point;  // two boxes touching at a corner
  point.lo = point.hi = Vec3(1, 1, 1);
  CHECK_THROWS_AS(make_roi_view(point, view_frame(0, 0), 64, 0.0), std::invalid_argument);
  const RoiView v = make_roi_view(point, view_frame(0, 0), 64, 1e-6);
  CHECK(v.half_depth > 0);
  CHECK(v.half_uv > 0);
}
