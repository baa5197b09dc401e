#pragma once
// Orthographic views of a ROI along d(theta, phi).
//
//        v ^            rays travel along +d; depth = dot(p - center, d), so larger depth is
//          |            farther from the viewer. The image is square, N x N texels, centred on
//          +---> u      the ROI centre and just large enough to hold the ROI box seen along d.
#include "peelcd/core/aabb.h"

#include <array>

namespace peelcd {

// d = (cos phi cos theta, cos phi sin theta, sin phi); theta = longitude, phi = latitude, degrees.
Vec3 view_direction(double theta_deg, double phi_deg);

struct ViewFrame {
  Vec3 u, v, d;  // right-handed orthonormal basis, d = viewing direction
};
// The frame of view direction d(theta, phi): u = normalize(up x d) with up = world z (world x
// near the poles), v = d x u; then u and v turned by `roll_deg` about d (counter-clockwise seen
// along -d). roll = 0 is the paper's frame.
ViewFrame view_frame(double theta_deg, double phi_deg, double roll_deg = 0.0);

struct RoiView {
  Aabb box;            // the (padded) ROI box, world
  Vec3 center;         // box centre, world; geometry is shifted by -center in double
  ViewFrame frame;
  double half_uv = 0;     // half side of the square image, world units
  double half_depth = 0;  // half of the depth range, world units
  int resolution = 0;     // N: image is N x N texels

  double texel() const { return 2.0 * half_uv / resolution; }
  // Column-major 4x4 from ROI-local position (p - center) to clip space: x, y in [-1, 1] over
  // the image, z in [-1, 1] over the depth range (window depth 0 = nearest).
  std::array<float, 16> clip_from_local() const;
  // World distance along d corresponding to a window-depth difference.
  double window_to_world_depth(double dz_window) const { return dz_window * 2.0 * half_depth; }
  double world_to_window_depth(double dz_world) const { return dz_world / (2.0 * half_depth); }
};

// `margin` pads the ROI box on every side (world units) so that a flat ROI (touching boxes)
// still has a depth range and clipping keeps surfaces lying on its faces.
RoiView make_roi_view(const Aabb& roi, const ViewFrame& frame, int resolution, double margin);

// Texels of padding around a ROI. A contact on the ROI boundary (two surfaces meeting at an
// edge of the box) is only seen with the surfaces just outside the box, so the box is grown by
// this many texels of the unpadded ROI's tile before clipping.
constexpr double kRoiPadTexels = 2.0;

// The view the pipeline peels: `roi` = intersection of boxes `a` and `b`, padded by
// kRoiPadTexels texels, and by 1e-6 of the objects' size so that a ROI without extent (boxes
// touching) keeps one.
RoiView make_padded_roi_view(const Aabb& roi, const Aabb& a, const Aabb& b, const ViewFrame& frame, int resolution);

}  // namespace peelcd
