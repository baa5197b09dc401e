#pragma once
// Layer dumps and goldens (docs/design.md section 5): every logical layer of every ROI view of one
// frame, losslessly, with the PCS, the colliding pairs and the metadata that produced them.
//
// On disk (peelcd dump --out DIR, and fixtures/golden/<case>/expected/):
//   DIR/meta.json                          renderer, GL version, options, shader hash, per view geometry
//   DIR/index.html                         the viewer (dumps only; self-contained)
//   DIR/<pair>/pcs.txt                     the pair's PCS over all views: "idA idB", sorted
//   DIR/<pair>/colliding.txt               "triA triB kind", sorted
//   DIR/<pair>/reference.txt               "triA triB": the exact reference of the two meshes, sorted
//   DIR/<pair>/view<v>/pcs.txt             that view's PCS
//   DIR/<pair>/view<v>/layer<kk>.exr       layer kk: Z (FLOAT, window depth), id (UINT, ID + 1,
//                                          0 = empty), object (UINT, 0 = A, 1 = B), dzdx, dzdy (FLOAT)
//   DIR/<pair>/view<v>/layer<kk>.png       preview (dumps only): depth | IDs, PCS texels marked
// EXR rows run top to bottom (row 0 = the top of the image, as image viewers show it).
// The format is specified for other writers in docs/dump-format.md (meta.json: the JSON Schema
// docs/schema/dump-meta.schema.json); kDumpFormat names its version.
#include "peelcd/core/frame.h"
#include "peelcd/core/texel.h"
#include "peelcd/core/detector.h"
#include "peelcd/gl/gl_stage.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace peelcd::oracle {

// meta.json's "format": the version of the dump format this code writes and reads.
inline constexpr const char* kDumpFormat = "peelcd.dump/1";

struct DumpView {
  std::string dir;  // relative to the dump root, e.g. "pair0_bunny_dragon/view0"
  int view = 0;
  int resolution = 0;
  bool a_first = false;
  float epsilon_window = 0, slope = 0;
  bool conservative = false;  // the frame's stage: intervals (words 0, 2: lower, upper depth)
  nlohmann::json geometry;  // centre, u, v, d, half_uv, half_depth, box (for the record)
  std::vector<std::vector<std::uint32_t>> layers;  // N*N*4 words each, GL row order (bottom first)
  std::vector<IdPair> pcs;
  // With the volume option (closed objects): per texel, the length along d where both objects
  // are inside (overlap_lengths(), peelcd/core/relation.h), written as inside.png; or why not.
  std::vector<float> inside;
  std::string inside_note;
};

struct DumpPair {
  std::string dir;  // e.g. "pair0_bunny_dragon"
  std::string name_a, name_b;
  std::size_t object_a = 0, object_b = 0;
  double epsilon = 0;
  std::vector<IdPair> pcs;
  std::vector<std::array<std::uint32_t, 2>> colliding;
  std::vector<std::string> kinds;  // ContactKind of each colliding pair
  // The exact reference of the two meshes (every intersecting triangle pair, sorted): what a
  // lossy configuration's misses are counted against. Absent (false) in a dump without it.
  bool has_reference = false;
  std::vector<std::array<std::uint32_t, 2>> reference;
  std::vector<DumpView> views;
};

struct Dump {
  std::string format = kDumpFormat;
  std::string renderer, gl_version, backend, shader_hash;
  nlohmann::json options;  // the DetectOptions of the frame
  nlohmann::json gl_options;  // the GL stage's settings (gl_options_to_json()); null: not recorded
  std::vector<DumpPair> pairs;
};

// Builds a dump from a frame and the views captured while it ran (Detector::capture_layers),
// with each pair's exact reference (exact_pair_reference(): a self pair's is exact_self_pairs()).
Dump make_dump(const FrameResult& frame, const std::vector<CapturedView>& captured,
               const std::vector<Object>& objects, const DetectOptions& options, const std::string& renderer,
               const std::string& gl_version, const std::string& backend, const gl::GlOptions* gl = nullptr);

// Writes `dump` to `dir` (created; must not exist or be empty). `previews` adds the PNG layer
// previews and index.html. Everything is written into a temporary sibling folder that is
// renamed at the end, so a failure leaves nothing behind. Throws InputError.
void write_dump(const Dump& dump, const std::string& dir, bool previews);

// Reads a dump written by write_dump or by any writer that follows docs/dump-format.md
// (previews are ignored). Throws InputError naming the file and the problem: a missing or
// malformed meta.json, a missing layer, a truncated or foreign EXR, a layer of the wrong size.
Dump read_dump(const std::string& dir);

// The texels where layer `k` of `view` took part in a PCS, by the test the stage used (recomputed
// on the CPU; used to mark previews): point sampling, layer k and k-1 of different objects within
// epsilon (pcs_within_epsilon); conservative, layer k's depth interval overlaps that of any layer
// of the other object at the texel (pcs_intervals_overlap).
std::vector<bool> pcs_texels(const DumpView& view, std::size_t k);

// Layer word accessors: peelcd/core/texel.h's, by the names the oracle has used.
inline bool texel_empty(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::empty(layer, i); }
inline std::uint32_t texel_object(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::object(layer, i); }
inline std::uint32_t texel_id1(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::id1(layer, i); }

// ---- images ----
// Writes one layer as EXR (see the layout above); reads it back into N*N*4 words. Throw InputError.
void write_layer_exr(const std::string& path, const std::vector<std::uint32_t>& layer, int n);
std::vector<std::uint32_t> read_layer_exr(const std::string& path, int& n);
// An 8-bit RGB image, rows top to bottom, written as PNG. Throws InputError.
struct Rgb {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // width * height * 3
  Rgb(int w, int h) : width(w), height(h), pixels(std::size_t(w) * h * 3, 0) {}
  void set(int x, int y, std::array<std::uint8_t, 3> c) {
    std::uint8_t* p = &pixels[(std::size_t(y) * width + x) * 3];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
};
void write_png(const std::string& path, const Rgb& image);
std::vector<std::uint8_t> encode_png(const Rgb& image);
// The preview of one layer: depth in grey (near = bright) | IDs in a stable palette, with the
// texels in `marks` (may be empty) in magenta on both halves.
Rgb layer_preview(const std::vector<std::uint32_t>& layer, int n, const std::vector<bool>& marks);

// ---- goldens ----
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
  };
  std::vector<LayerCount> per_layer;  // layers with any difference
  bool ok() const { return failures.empty() && differing_texels == 0; }
};

Comparison compare_dumps(const Dump& expected, const Dump& actual, Tier tier, std::size_t max_listed = 10);

// Human report (the same text compare prints) plus, for up to `max_layers` differing layers,
// <view>_layer<kk>_{expected,actual,error}.png in `dir` (created). Returns the report text.
std::string write_report(const Dump& expected, const Dump& actual, const Comparison& comparison,
                         const std::string& case_name, const std::string& dir, std::size_t max_layers = 4);
std::string report_text(const Comparison& comparison, const std::string& case_name, Tier tier);

}  // namespace peelcd::oracle
