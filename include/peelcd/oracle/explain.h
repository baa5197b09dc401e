#pragma once
// Why a contact was found or missed: `peelcd explain` and `detect --explain-misses`
// (docs/debugging.md). One frame is run with every layer captured (FrameTrace); for one triangle
// pair the trace then answers, in the pipeline's order:
//   1. the exact answer: do the triangles intersect, the contact kind, the segment;
//   2. the ROI: do the objects' boxes overlap, was the ROI routed to the exact CPU path, did
//      culling keep each triangle (and if not, which test dropped it);
//   3. per ROI view: was each triangle drawn, where its own fragments land (a second, two-triangle
//      run of the CPU image stage: the rasterization model of peelcd/core/image/cpu_stage.h), the
//      texels the segment crosses, the layers the stage produced there (object, ID, depth or depth
//      interval, in peel order), the PCS tests that involve the two triangles' IDs and their values
//      against the threshold (epsilon window + slope term, or interval overlap);
//   4. a verdict: found (view, texel), or missed and the first reason.
// The layers are the stage's own (GL or CPU); only "where would this triangle alone land" comes
// from the model, so at a texel centre within rounding of an edge the two may disagree (said so in
// the report as "model" versus "layers").
#include "peelcd/core/image/detector.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace peelcd::oracle {

// The pair to explain: object indices (any order; reported in the frame's order, A < B) and a
// triangle index of each.
struct PairQuery {
  std::size_t object_a = 0, object_b = 0;
  std::uint32_t tri_a = 0, tri_b = 0;
};

// Parses "OBJ_A:TRI_A,OBJ_B:TRI_B" where OBJ is an object's name or index in `objects`.
// Throws InputError naming the problem (unknown object, triangle out of range, same object).
PairQuery parse_pair_query(const std::string& text, const std::vector<Object>& objects);

// The verdicts, in the order the pipeline can lose a pair.
enum class Verdict {
  found,           // reported by the frame (image stage: in which view and texel)
  found_exact,     // reported by the frame, through the exact CPU path (the router's choice)
  no_roi,          // the objects' boxes do not overlap (never for an intersecting pair)
  culled,          // a triangle was dropped before drawing (never for an intersecting pair)
  edge_on,         // a triangle is drawn but has no fragment: seen edge-on
  sub_texel,       // tile too coarse: a triangle or the segment falls between texel centres
  separated,       // both surfaces are at a texel, but a layer of the same object is between
  above_epsilon,   // adjacent layers, depth difference above the threshold
  not_located,     // missed, and no texel explains it (a model/stage disagreement)
  no_contact,      // the triangles do not intersect and were not reported
};
const char* to_string(Verdict v);

// One layer at a texel, as the stage produced it.
struct TexelLayer {
  int layer = 0;
  std::uint32_t object = 0;      // 0 = A, 1 = B
  std::uint32_t id = 0;          // the layer's triangle ID
  float depth = 0, depth_hi = 0; // window depth (conservative: the interval)
  bool stands_a = false, stands_b = false;  // the ID stands for the queried triangle of A / B
};

// A PCS test at a texel between a layer standing for A's triangle and one standing for B's.
struct TexelTest {
  int layer_a = 0, layer_b = 0;
  float value = 0, bound = 0;  // |dz| and epsilon_window + slope * spread; conservative: the gap
                               // between the intervals (<= 0 overlaps) and 0
  bool adjacent = true;        // lossy: the two layers are adjacent (only those are tested)
  bool pass = false;
};

struct TexelReport {
  int x = 0, y = 0;                   // texel column and row (row 0 at the bottom)
  bool model_a = false, model_b = false;  // the triangle alone covers this texel (model)
  float model_depth_a = 0, model_depth_b = 0;
  std::vector<TexelLayer> layers;     // every layer at the texel, in peel order
  std::vector<TexelTest> tests;       // tests between layers standing for A's and B's triangles
  Verdict status = Verdict::no_contact;  // this texel's own answer (found, separated, ...)
  std::string note;                   // one line
};

struct ViewReport {
  int view = 0;
  int resolution = 0;
  double texel = 0;                   // world units per texel
  float epsilon_window = 0, slope = 0;
  bool conservative = false;
  bool drawn_a = false, drawn_b = false;  // the triangle is in this view's draw list
  bool exhaustive = false;            // the view was resolved by box tests (k-buffer too deep)
  std::size_t fragments_a = 0, fragments_b = 0;  // model fragments of each triangle
  std::size_t common_texels = 0;      // texels both cover (model)
  std::array<std::array<double, 2>, 3> window_a{}, window_b{};  // projected corners, texels
  std::array<std::array<double, 2>, 2> segment{};              // projected segment, texels
  double segment_texels = 0;          // its projected length
  std::vector<TexelReport> texels;    // the segment's texels, then other common texels (capped)
  std::size_t segment_texel_count = 0;  // the first this many of `texels` lie on the segment
  bool pcs_found = false;             // the view's PCS, expanded, hold the pair
  int found_x = -1, found_y = -1;     // first texel whose test reported it
  std::size_t found_texels = 0;
  Verdict reason = Verdict::no_contact;
  std::string summary;                // one line
  // A crop of the view around the segment for the page: per texel (rows bottom to top) flags
  // 1 = A's triangle (model), 2 = B's, 4 = the pair's test passed here; depth of layer 0 or NaN.
  int crop_x = 0, crop_y = 0, crop_w = 0, crop_h = 0;
  std::vector<std::uint8_t> crop_flags;
  std::vector<float> crop_depth;
};

struct Explanation {
  PairQuery query;                 // normalised: object_a < object_b
  std::string name_a, name_b;
  nlohmann::json options;          // the frame's options
  std::string backend, renderer;
  // The exact answer.
  bool intersect = false;
  bool adjacent = false;  // a self couple (one object's two triangles) that shares a vertex: never a pair
  std::string kind;                // crossing, touching, coplanar, degenerate ("" when disjoint)
  Vec3 p = Vec3::Zero(), q = Vec3::Zero();
  // The frame.
  bool roi = false;                // the objects' boxes overlap
  bool exact_path = false;         // the ROI was routed to the exact CPU path
  double predicted_exact_ms = 0, predicted_image_ms = 0;
  bool kept_a = true, kept_b = true;  // culling kept the triangle
  std::string cull_a, cull_b;      // why not
  std::uint32_t id_a = 0, id_b = 0;   // the IDs the triangles write (the provoking corner's)
  bool candidate = false;          // the pair was a candidate of the narrow phase
  bool reported = false;           // the frame reported the pair as colliding
  std::vector<ViewReport> views;
  Verdict verdict = Verdict::no_contact;
  std::string verdict_line;        // one line
  // With the depth option: the object pair's penetration direction and depth (peelcd/core/exact/depth.h).
  bool depth_asked = false;
  PenetrationDepth depth;
};

// One frame run with every layer captured, for explaining any number of pairs of it.
class FrameTrace {
 public:
  // Runs `detector` on `objects` under `options` (as detect would: same routing, tiles, views).
  FrameTrace(Detector& detector, const std::vector<Object>& objects, const DetectOptions& options);
  Explanation explain(const PairQuery& query) const;
  const FrameResult& result() const { return result_; }

 private:
  const std::vector<Object>& objects_;
  DetectOptions options_;
  std::string backend_, renderer_;
  FrameResult result_;
  std::vector<CapturedView> captured_;
};

nlohmann::json to_json(const Explanation& e);
std::string explain_text(const Explanation& e);
// Writes DIR/index.html (the report, one zoomed picture per view with the two triangles outlined
// and the segment drawn), DIR/view<v>.png and DIR/explain.json; DIR must not exist or be empty,
// written into DIR.partial and renamed. Throws InputError.
void write_explain_page(const Explanation& e, const std::string& dir);

}  // namespace peelcd::oracle
