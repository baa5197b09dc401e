#include "peelcd/core/planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace peelcd {

namespace {
// Fitted by `peelcd calibrate` on the 2-core machine docs/performance.md names: 0.16 us per
// triangle kept by the first culling round (the router's count), no fixed part measurable.
constexpr double kExactViewMs = 0.0;
constexpr double kExactTriangleUs = 0.16;
// The scan of culling's first round, per triangle of the two objects (`peelcd calibrate`, large
// meshes; docs/performance.md).
constexpr double kScanUs = 0.055;
}  // namespace

StageCost exact_path_cost() {
  return StageCost{kExactViewMs, kExactTriangleUs, 0.0, kScanUs};
}

StageCost world_exact_cost() { return StageCost{0.0, kWorldCandidateUs, 0.0, 0.0}; }

bool margin_too_wide_for_image(const DetectOptions& opt, const Aabb& roi) {
  if (!(opt.margin > 0.0) || roi.empty()) return false;
  const Aabb grown = roi.grown(opt.margin);
  const double float_max = double(std::numeric_limits<float>::max());
  if (!(grown.lo.cwiseAbs().maxCoeff() <= float_max && grown.hi.cwiseAbs().maxCoeff() <= float_max)) return true;
  return opt.margin > kImageMarginShare * roi.extent().maxCoeff();
}

Route route_pair(const DetectOptions& opt, const StageCost& exact, const StageCost& image, double scanned, double work,
                 int tile) {
  Route r;
  if (opt.stage != Stage::automatic) {
    r.exact = opt.stage == Stage::exact;
    return r;
  }
  const double scan = exact.scan_us * 1e-3 * scanned;  // paid by both paths
  r.predicted_exact_ms = scan + exact.predict_ms(work, 0.0);
  r.predicted_image_ms = scan + double(opt.views) * image.predict_ms(work, double(tile) * double(tile));
  r.exact = r.predicted_exact_ms <= r.predicted_image_ms;
  return r;
}

std::size_t fused_view_frames(const DetectOptions& o, ViewFrame out[3]) {
  const ViewFrame f = view_frame(o.theta, o.phi, o.roll);
  out[0] = f;
  if (o.views < 1 || o.views > 3) throw std::invalid_argument("peelcd: views must be 1, 2 or 3");
  // Along d, then along u, then along v: each view is the previous one turned a quarter turn.
  if (o.views >= 2) out[1] = ViewFrame{f.v, f.d, f.u};
  if (o.views == 3) out[2] = ViewFrame{f.d, f.u, f.v};
  return std::size_t(o.views);
}

std::vector<ViewFrame> fused_view_frames(const DetectOptions& o) {
  ViewFrame f[3];
  const std::size_t n = fused_view_frames(o, f);
  return std::vector<ViewFrame>(f, f + n);
}

int edge_tile_resolution(int share, const Aabb& region, double median_edge, double edge_texels) {
  if (!(edge_texels > 0.0) || !(median_edge > 0.0) || !std::isfinite(median_edge) || region.empty()) return share;
  const Vec3 extent = region.hi - region.lo;
  const double texels = std::ceil(edge_texels * extent.maxCoeff() / median_edge);
  if (!(texels < double(share))) return share;  // also NaN-safe
  const int n = std::max(16, int(std::ceil(texels / 16.0)) * 16);
  return std::min(n, share);
}

double edge_texels_of(const DetectOptions& o) {
  if (o.edge_texels) return *o.edge_texels;
  return o.conservative ? kConservativeEdgeTexels : kPointEdgeTexels;
}

void allocate_tiles(int budget, const std::vector<int>& needs, std::vector<int>& tiles) {
  tiles.assign(needs.begin(), needs.end());
  double area = 0.0;
  for (const int n : needs) area += double(n) * double(n);
  const double total = double(budget) * double(budget);
  if (!(area > total)) return;
  const double scale = std::sqrt(total / area);
  for (int& t : tiles) t = std::max(16, int(std::floor(double(t) * scale / 16.0)) * 16);
  for (std::size_t i = 0; i < tiles.size(); ++i) tiles[i] = std::min(tiles[i], needs[i]);
}

int tile_resolution(int budget, std::size_t roi_count) {
  if (budget <= 0) throw std::invalid_argument("peelcd::tile_resolution(): budget must be positive");
  int n = budget;
  std::size_t per_side = 1;
  while (per_side * per_side < roi_count && n > 16) {
    per_side *= 2;
    n /= 2;
  }
  return std::max(n, std::min(budget, 16));
}

}  // namespace peelcd
