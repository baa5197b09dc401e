#include "peelcd/core/image/view.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace peelcd {

Vec3 view_direction(double theta_deg, double phi_deg) {
  const double t = theta_deg * M_PI / 180.0, p = phi_deg * M_PI / 180.0;
  return Vec3(std::cos(p) * std::cos(t), std::cos(p) * std::sin(t), std::sin(p)).normalized();
}

ViewFrame view_frame(double theta_deg, double phi_deg, double roll_deg) {
  ViewFrame f;
  f.d = view_direction(theta_deg, phi_deg);
  // Helper "up" axis: world z unless d is nearly parallel to it (the poles).
  const Vec3 up = std::abs(f.d.z()) < 0.9 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
  f.u = up.cross(f.d).normalized();
  f.v = f.d.cross(f.u).normalized();
  if (roll_deg != 0.0) {
    const double r = roll_deg * M_PI / 180.0, c = std::cos(r), s = std::sin(r);
    const Vec3 u = f.u, v = f.v;
    f.u = (c * u + s * v).normalized();
    f.v = f.d.cross(f.u).normalized();
  }
  return f;
}

std::array<float, 16> RoiView::clip_from_local() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m.block<1, 3>(0, 0) = frame.u.transpose() / half_uv;
  m.block<1, 3>(1, 0) = frame.v.transpose() / half_uv;
  m.block<1, 3>(2, 0) = frame.d.transpose() / half_depth;
  m(3, 3) = 1.0;
  std::array<float, 16> out{};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[c * 4 + r] = static_cast<float>(m(r, c));
  return out;
}

RoiView make_roi_view(const Aabb& roi, const ViewFrame& frame, int resolution, double margin) {
  if (roi.empty()) throw std::invalid_argument("peelcd::make_roi_view(): empty ROI");
  if (resolution <= 0) throw std::invalid_argument("peelcd::make_roi_view(): resolution must be positive");
  RoiView view;
  view.box = roi;
  view.box.lo.array() -= margin;
  view.box.hi.array() += margin;
  view.center = view.box.center();
  view.frame = frame;
  view.resolution = resolution;
  const Vec3 h = 0.5 * view.box.extent();
  const auto half_along = [&](const Vec3& axis) { return axis.cwiseAbs().dot(h); };
  view.half_uv = std::max(half_along(frame.u), half_along(frame.v));
  view.half_depth = half_along(frame.d);
  if (!(view.half_uv > 0.0) || !(view.half_depth > 0.0))
    throw std::invalid_argument("peelcd::make_roi_view(): ROI has no extent; pass a positive margin");
  return view;
}

RoiView make_padded_roi_view(const Aabb& roi, const Aabb& a, const Aabb& b, const ViewFrame& frame, int resolution) {
  const double scale = std::max(a.extent().norm(), b.extent().norm());
  // Also a few ulps of the coordinates' magnitude: two boxes that are one point far from the
  // origin (zero-area triangles at the same place) still get a box with extent.
  const double magnitude = std::max({roi.lo.cwiseAbs().maxCoeff(), roi.hi.cwiseAbs().maxCoeff(), 1e-300});
  const double floor = std::max(1e-6 * scale + std::numeric_limits<double>::min(),
                                64.0 * std::numeric_limits<double>::epsilon() * magnitude);
  const RoiView tight = make_roi_view(roi, frame, resolution, floor);
  return make_roi_view(roi, frame, resolution, floor + kRoiPadTexels * tight.texel());
}

}  // namespace peelcd
