#pragma once
// Settings of the GL image stage (peelcd/gl/gl_stage.h) that the backend-neutral detector does
// not know about. No GL here: scene files and the command line parse them too.
#include <optional>
#include <string>
#include <vector>

namespace peelcd {

// How the layers are produced on the GPU; both give the same layers and PCS, bit for bit
// (the goldens check it). multipass: one draw per layer with a strict depth test against the
// previous layer (the paper's way). abuffer: both objects drawn once into per-texel fragment
// lists, the layers recovered per texel by one compute pass (shaders/abuffer_resolve.comp).
enum class Peeler { multipass, abuffer };

// Where the single-pass peeler's k-buffer is resolved into layers and PCS: gpu (a compute pass,
// shaders/abuffer_resolve.comp; the PCS list is read back), host (the k-buffer is mapped and
// resolved by core/image/kbuffer.h: the same layers and PCS), or automatic: host where GL renders on
// the CPU (llvmpipe, softpipe: the buffers are host memory already), gpu elsewhere.
enum class Resolve { automatic, gpu, host };

// How conservative views find the texels each triangle touches; both store the same fragments,
// bit for bit (the goldens check it). raster: the rasterizer, through a quad per triangle
// (shaders/conservative.{vert,geom,frag}). compute: one compute invocation per triangle loops
// over the texels of that quad (shaders/conservative_cover.comp), with the same arithmetic
// (shaders/conservative.inc): for a device whose raster engine is the bottleneck
// (docs/backends.md, "Raster or compute for coverage"). automatic: the one `peelcd calibrate
// --write-costs` timed faster on this device and renderer when the stage routes by such a file
// (CostModels::coverage), else compute on a GPU (the faster on the World's batched frames of an
// NVIDIA H200) and raster on a software renderer. Point-sampled views always rasterize.
enum class Coverage { automatic, raster, compute };

inline const char* to_string(Peeler peeler) { return peeler == Peeler::abuffer ? "abuffer" : "multipass"; }

inline std::optional<Peeler> parse_peeler(const std::string& text) {
  if (text == "abuffer" || text == "single-pass") return Peeler::abuffer;
  if (text == "multipass") return Peeler::multipass;
  return std::nullopt;
}

inline const char* to_string(Resolve resolve) {
  return resolve == Resolve::gpu ? "gpu" : resolve == Resolve::host ? "host" : "auto";
}

inline std::optional<Resolve> parse_resolve(const std::string& text) {
  if (text == "auto") return Resolve::automatic;
  if (text == "gpu") return Resolve::gpu;
  if (text == "host") return Resolve::host;
  return std::nullopt;
}

inline const char* to_string(Coverage coverage) {
  return coverage == Coverage::compute ? "compute" : coverage == Coverage::raster ? "raster" : "auto";
}

inline std::optional<Coverage> parse_coverage(const std::string& text) {
  if (text == "auto") return Coverage::automatic;
  if (text == "raster") return Coverage::raster;
  if (text == "compute") return Coverage::compute;
  return std::nullopt;
}

namespace gl {

struct GlOptions {
  Peeler peeler = Peeler::abuffer;        // chosen on peelcd bench (docs/performance.md)
  Resolve resolve = Resolve::automatic;   // single-pass peeler only
  // Threads of the host resolve (Resolve::host): 0 = the hardware's threads, at most 8.
  unsigned workers = 0;
  // The views of a frame are packed into one k-buffer and drawn together (a count and a fill draw
  // per frame: GlImageStage::peel_batch): conservative views, and point-sampled views of the
  // abuffer peeler that capture no layers; false draws each view on its own (the same layers and
  // PCS; for comparison: peelcd detect/simulate --no-batch).
  bool batch = true;
  // In a batch, the triangles of rigid objects are selected on the GPU (two compute passes over
  // each shape's resident corners, per view: those reaching the view's ROI box and the contact
  // region of both objects' triangles there; drawn by one indirect draw) instead of by the
  // host's culling: no per-triangle upload for rigid objects after a shape's first frame. Neither
  // drops a triangle that touches the other object: conservative, the contacts are the same
  // (the PCS differ where the two keep different triangles near the contact); point sampled,
  // the triangles the host's culling had removed can change the layers (and what point sampling
  // misses), as between culling modes. Views capturing layers (dumps, goldens) keep the host's
  // selection. false: the host's (peelcd detect --cpu-select).
  bool gpu_select = true;
  // Conservative views resolved on the GPU in a batch: a couple whose two triangles are certainly
  // farther apart than the margin (a separating axis in float that no rounding can close,
  // peelcd/core/image/certified_apart.inc) is dropped on the GPU; only the couples that may touch
  // come back to the host's exact test. The contacts are the same; the PCS are those couples.
  // Dumps and goldens turn it off (their PCS are the image stage's). false: every overlapping
  // couple comes back (peelcd detect --no-gpu-filter).
  bool gpu_filter = true;
  // Conservative views' coverage: the rasterizer or a compute pass (Coverage above); the same
  // layers and PCS. `peelcd calibrate` times both on the device and records the faster.
  Coverage coverage = Coverage::automatic;
  // Coverage by compute: a triangle whose box holds more texels than this has them walked by the
  // 64 invocations of its workgroup together rather than by its own (shaders/conservative_cover.comp;
  // 0: every triangle's; below -1: none). -1 (the default): 16 on a GPU, none on a software
  // renderer (which runs a group's invocations in turn: there sharing cost 3-6x). The same
  // fragments either way; a tuning value, not in the option table below (the command line and
  // scene files keep the default).
  int cover_share_texels = -1;
};

// The GL stage's settings, one row each, as the frame's option table (peelcd/core/options.h)
// holds the frame's: the key is the scene file's (top level), the JSON's ("gl_options" of a
// result and of a dump's meta.json) and the Python keyword; `flag` the command line's. Values
// are words: a choice's, or "true" / "false" for a boolean (JSON writes booleans as such).
struct GlOptionSpec {
  const char* key;      // "peeler"
  const char* flag;     // "--peeler"; a boolean's flag turns it off ("--no-batch")
  const char* help;     // one sentence
  const char* choices;  // "abuffer,multipass"; "" for a boolean
  std::string (*get)(const GlOptions&);
  bool (*set)(GlOptions&, const std::string&);  // false: not a value of the row
};

inline const std::vector<GlOptionSpec>& gl_option_table() {
  static const std::vector<GlOptionSpec> table = {
      {"peeler", "--peeler",
       "How layers are made: abuffer (one draw into a per-texel k-buffer) or multipass (one draw per layer, the paper's)",
       "abuffer,multipass", [](const GlOptions& o) { return std::string(to_string(o.peeler)); },
       [](GlOptions& o, const std::string& v) {
         const auto p = parse_peeler(v);
         if (p) o.peeler = *p;
         return bool(p);
       }},
      {"resolve", "--resolve",
       "Where the k-buffer becomes layers and PCS: auto (host on a software renderer, else gpu), gpu (on a "
       "software renderer also the World's image pairs batched, as on a GPU) or host",
       "auto,gpu,host", [](const GlOptions& o) { return std::string(to_string(o.resolve)); },
       [](GlOptions& o, const std::string& v) {
         const auto r = parse_resolve(v);
         if (r) o.resolve = *r;
         return bool(r);
       }},
      {"batch", "--no-batch",
       "Pack a frame's views into one k-buffer drawn together (false: each view on its own)", "",
       [](const GlOptions& o) { return std::string(o.batch ? "true" : "false"); },
       [](GlOptions& o, const std::string& v) {
         if (v != "true" && v != "false") return false;
         o.batch = v == "true";
         return true;
       }},
      {"gpu_select", "--cpu-select",
       "In a batch, select rigid objects' triangles on the GPU (false: the host's culling selects them)", "",
       [](const GlOptions& o) { return std::string(o.gpu_select ? "true" : "false"); },
       [](GlOptions& o, const std::string& v) {
         if (v != "true" && v != "false") return false;
         o.gpu_select = v == "true";
         return true;
       }},
      {"gpu_filter", "--no-gpu-filter",
       "In a conservative batch resolved on the GPU, drop couples whose triangles are certainly apart (false: all come back)",
       "", [](const GlOptions& o) { return std::string(o.gpu_filter ? "true" : "false"); },
       [](GlOptions& o, const std::string& v) {
         if (v != "true" && v != "false") return false;
         o.gpu_filter = v == "true";
         return true;
       }},
      {"coverage", "--coverage",
       "How conservative views find the texels a triangle touches: raster (the rasterizer), compute (a compute "
       "pass, the same layers) or auto (the faster by the cost models of peelcd calibrate, else compute on a GPU and raster "
       "on a software renderer)",
       "auto,raster,compute", [](const GlOptions& o) { return std::string(to_string(o.coverage)); },
       [](GlOptions& o, const std::string& v) {
         const auto c = parse_coverage(v);
         if (c) o.coverage = *c;
         return bool(c);
       }},
  };
  return table;
}

// Sets row `key` of `options` to `value` (words); returns the problem in words, empty if none
// ("unknown GL option \"x\"", "resolve: unknown value \"fast\" (expected auto, gpu or host)").
inline std::string set_gl_option(GlOptions& options, const std::string& key, const std::string& value) {
  for (const GlOptionSpec& spec : gl_option_table()) {
    if (key != spec.key) continue;
    if (spec.set(options, value)) return {};
    std::string expected = *spec.choices ? spec.choices : "true,false";
    for (char& c : expected)
      if (c == ',') c = '/';
    return key + ": unknown value \"" + value + "\" (expected " + expected + ")";
  }
  return "unknown GL option \"" + key + "\"";
}

}  // namespace gl
}  // namespace peelcd
