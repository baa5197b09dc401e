#include "peelcd/core/image/planner.h"

#include <algorithm>
#include <cstdio>
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

const char* pair_path(const PairResult& p) {
  if (p.exact_stage) return "exact";
  if (p.views_peeled == 0) return "none";
  if (p.views_exhaustive == 0) return "image";
  return p.views_exhaustive == p.views_peeled ? "exhaustive" : "image+exhaustive";
}

std::string pair_path_reason(const PairResult& p, const DetectOptions& o) {
  char buf[320];
  if (p.exact_stage) {
    if (o.stage == Stage::exact) return "--stage exact";
    if (p.margin_fallback) {
      std::snprintf(buf, sizeof buf,
                    "the margin %g is wider than %g of the ROI's longest side (or its view leaves the float range): "
                    "the image stage would grow every triangle over much of the view; tested on the exact CPU path",
                    o.margin, kImageMarginShare);
      return buf;
    }
    if (p.object_a == p.object_b) {
      std::snprintf(buf, sizeof buf,
                    "a self pair: the exact CPU path under --stage auto (predicted at %.3f ms by its candidate couples)",
                    p.predicted_exact_ms);
      return buf;
    }
    std::snprintf(buf, sizeof buf, "routed: the exact CPU path was predicted at %.3f ms, the image stage at %.3f ms",
                  p.predicted_exact_ms, p.predicted_image_ms);
    return buf;
  }
  if (p.views_peeled == 0) return "contact culling kept no triangle of one object: no contact possible";
  const std::string why = o.stage == Stage::image ? std::string("--stage image") : [&] {
    std::snprintf(buf, sizeof buf, "routed: the image stage was predicted at %.3f ms, the exact CPU path at %.3f ms",
                  p.predicted_image_ms, p.predicted_exact_ms);
    return std::string(buf);
  }();
  if (p.views_exhaustive == 0) return why;
  std::snprintf(buf, sizeof buf,
                "; %d of %d views too deep or too large (%dx%d) for the image stage's k-buffer: their triangles' "
                "box-overlapping couples were tested exactly instead (no layers, no PCS)",
                p.views_exhaustive, p.views_peeled, p.resolution, p.resolution);
  return why + buf;
}

}  // namespace peelcd
