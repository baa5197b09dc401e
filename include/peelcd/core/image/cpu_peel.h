#pragma once
// A CPU model of the image stage: casts one ray per texel centre through a ROI, collects every
// hit of both objects inside the ROI box, and applies the layer rules of docs/design.md section 1.5
// (alternate peeling) or of the `full` mode (every surface; every adjacent A-B couple). It is
// an independent oracle for the GL pipeline's layers and PCS, up to rasterization rules at
// triangle edges (a texel centre exactly on a shared edge is owned by one triangle in GL and
// by both here) and float rounding of depth.
#include "peelcd/core/frame.h"
#include "peelcd/core/image/view.h"

#include <vector>

namespace peelcd {

struct CpuPeelResult {
  int layers = 0;            // deepest non-empty logical layer count over all texels
  std::vector<IdPair> pcs;   // sorted, unique
};

// `a_first`: object A is peeled first (alternate mode). `slope` as in DetectOptions. Depth
// comparisons are done in double. With `only_a` / `only_b`, just the triangles listed are cast
// against (contact-region culling, core/image/cull.h).
CpuPeelResult cpu_peel(const Mesh& a, const Mesh& b, const RoiView& view, IdMode ids, double epsilon,
                       bool a_first, PeelMode mode, double slope, const std::vector<std::uint32_t>* only_a = nullptr,
                       const std::vector<std::uint32_t>* only_b = nullptr);

}  // namespace peelcd
