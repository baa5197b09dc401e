#pragma once
// The dump format (docs/design.md section 5): every logical layer of every ROI view of one
// frame, losslessly, with the PCS, the colliding pairs and the metadata that produced them.
//
// On disk (peelcd dump --out DIR, and fixtures/golden/<case>/expected/):
//   DIR/meta.json                          renderer, GL version, options, shader hash, per view geometry
//   DIR/index.html                         the viewer (dumps only; self-contained)
//   DIR/<pair>/pcs.txt                     the pair's PCS over all views: "idA idB", sorted
//   DIR/<pair>/colliding.txt               "triA triB kind", sorted
//   DIR/<pair>/reference.txt               "triA triB": the exact reference of the two meshes, sorted
//   DIR/<pair>/missed.txt                  (dumps only, where the frame missed reference pairs)
//                                          "triA triB verdict: why", peelcd explain's verdict on
//                                          the same frame, sorted; at most kMissedExplained
//   DIR/<pair>/view<v>/pcs.txt             that view's PCS
//   DIR/<pair>/view<v>/layer<kk>.exr       layer kk: Z (FLOAT, window depth), id (UINT, ID + 1,
//                                          0 = empty), object (UINT, 0 = A, 1 = B), dzdx, dzdy (FLOAT)
//   DIR/<pair>/view<v>/layer<kk>.png       preview (dumps only): depth | IDs, PCS texels marked
// EXR rows run top to bottom (row 0 = the top of the image, as image viewers show it).
// The format is specified for other writers in docs/dump-format.md (meta.json: the JSON Schema
// docs/schema/dump-meta.schema.json); kDumpFormat names its version.
#include "peelcd/core/frame.h"
#include "peelcd/core/image/texel.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/gl/gl_stage.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace peelcd::oracle {

// meta.json's "format": the version of the dump format this code writes and reads.
inline constexpr const char* kDumpFormat = "peelcd.dump/1";
// Missed pairs a dump explains (peelcd dump): each costs an explanation on the captured frame.
inline constexpr std::size_t kMissedExplained = 500;

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
  // are inside (overlap_lengths(), peelcd/core/exact/relation.h), written as inside.png; or why not.
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
  // Reference pairs the frame did not report, with peelcd explain's verdict on the same frame
  // (peelcd dump fills it, at most kMissedExplained; the viewer lists every missed pair).
  struct Missed {
    std::uint32_t tri_a = 0, tri_b = 0;
    std::string verdict, why;  // to_string(Verdict), explain's one line
  };
  std::vector<Missed> missed;
  // For the viewer (peelcd dump; not in the files): the ID each triangle of a colliding or
  // missed pair writes in the layers (corner_id() of its provoking corner), by triangle.
  std::map<std::uint32_t, std::uint32_t> ids_a, ids_b;
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

// A layer's file stem in a view's folder: layer<kk> (two digits at least).
std::string layer_name(std::size_t k);
// The pair's reference pairs the frame did not report (reference less colliding, sorted).
std::vector<std::array<std::uint32_t, 2>> missed_pairs(const DumpPair& pair);

// Layer word accessors: peelcd/core/image/texel.h's, by the names the oracle has used.
inline bool texel_empty(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::empty(layer, i); }
inline std::uint32_t texel_object(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::object(layer, i); }
inline std::uint32_t texel_id1(const std::vector<std::uint32_t>& layer, std::size_t i) { return texel::id1(layer, i); }

}  // namespace peelcd::oracle
