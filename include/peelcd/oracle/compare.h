#pragma once
// Comparing two dumps (a golden and a run): the tiers, their tolerances, the comparison and its
// report (docs/golden-images.md).
#include "peelcd/oracle/format.h"

#include <cstddef>
#include <string>
#include <vector>

namespace peelcd::oracle {

// How a backend is compared with the OSMesa goldens (docs/design.md section 5).
//   exact:    llvmpipe in any context (OSMesa, EGL surfaceless): every layer word equal, the same
//             layer counts, the same PCS and colliding pairs.
//   hardware: another rasterizer. Texels: IDs may differ within kIdSilhouetteTexels of an edge of
//             the golden layer, depths by max(kDepthTolerance, kDepthFractionOfEpsilon x epsilon) on the same surface, slopes are free; a
//             layer only one side has may hold only edge texels (a sliver). Pairs: in the
//             conservative mode the colliding set must be equal; in a lossy configuration the
//             misses against the exact reference may exceed the golden's by at most
//             hardware_miss_slack(reference size). PCS and layer counts may differ (listed).
enum class Tier { exact, hardware };

// Hardware tier tolerances, each with its reason (docs/golden-images.md).
// IDs may differ within this many texels of a silhouette or triangle edge of the golden layer:
// rasterizers snap vertices to different sub-texel grids and break ties on edges through texel
// centres differently, so a texel next to an edge can go to either side.
inline constexpr int kIdSilhouetteTexels = 1;
// Depths may differ where the same triangle covers the texel (the depth plane is interpolated in
// another order and precision) by kDepthFractionOfEpsilon of the view's PCS threshold
// (epsilon_window), and at least kDepthTolerance (window depth, [0, 1] over the ROI's depth
// range; the conservative mode has no threshold). A depth error of 1% of epsilon moves a PCS
// decision only for a pair within 1% of the threshold; 2^-16 = 1.5e-5 is 256 float ULPs at depth
// 1 and 128 times below one texel's depth at 512^2.
inline constexpr double kDepthFractionOfEpsilon = 0.01;
inline constexpr double kDepthTolerance = 1.0 / 65536.0;
// On steep triangles, also the texel's depth slope (|dzdx| + |dzdy|) times 1/256 texel: GPUs and
// llvmpipe snap vertices to 8 sub-texel bits, each to its own grid, which moves the depth plane
// by up to that much. With ring or paper IDs (one ID for several triangles) a depth within the
// golden depths of the same ID in the 3 x 3 texels around is also accepted: the edge between two
// triangles of one ID moved by a texel, which near_edge cannot see.
inline constexpr double kSnapTexels = 1.0 / 256.0;
// The PCS threshold and slope factor of a view are host arithmetic; another implementation may
// round them differently in float: relative difference allowed.
inline constexpr double kThresholdRelative = 1e-5;
// A lossy configuration (point sampling) misses pairs whose contact covers few texel centres;
// a one-texel edge shift changes which of them are sampled. The golden's misses plus this slack
// (2 pairs, plus 5% of the reference) bound a hardware backend's misses.
inline constexpr std::size_t kMissSlackPairs = 2;
inline constexpr double kMissSlackFraction = 0.05;
std::size_t hardware_miss_slack(std::size_t reference_pairs);
const char* to_string(Tier tier);

struct TexelDifference {
  std::string view_dir;
  std::size_t layer = 0;
  int x = 0, y = 0;  // image coordinates, y = 0 at the top (as in the EXR and PNG files)
  std::string channel, expected, actual;
};

struct Comparison {
  std::vector<std::string> failures;  // structural differences, PCS, pairs: one line each
  std::vector<std::string> notes;     // differences that do not fail the tier
  std::size_t differing_texels = 0;   // beyond the tier's tolerance
  std::size_t tolerated_texels = 0;   // within it (hardware tier)
  std::vector<TexelDifference> first; // the first differing texels, in (view, layer, y, x) order
  struct LayerCount {
    std::string view_dir;
    std::size_t layer;
    std::size_t differing, tolerated;
    // Per texel, image order (top row first): 0 the same, 1 different within the tier's
    // tolerance, 2 beyond it. Kept for layers with a difference (empty otherwise).
    std::vector<std::uint8_t> texels;
  };
  std::vector<LayerCount> per_layer;  // layers with any difference
  bool ok() const { return failures.empty() && differing_texels == 0; }
};

Comparison compare_dumps(const Dump& expected, const Dump& actual, Tier tier, std::size_t max_listed = 10);

// Human report (the same text compare prints) plus, for up to `max_layers` differing layers,
// <view>_layer<kk>_{expected,actual,error}.png in `dir` (created; error: red beyond the tier's
// tolerance, yellow within it) and index.html: those layers side by side with a readout of both
// dumps' words at the hovered texel. Returns the report text.
std::string write_report(const Dump& expected, const Dump& actual, const Comparison& comparison,
                         const std::string& case_name, const std::string& dir, std::size_t max_layers = 4);
std::string report_text(const Comparison& comparison, const std::string& case_name, Tier tier);

}  // namespace peelcd::oracle
