// peelcd: image-space collision detection through alternate surface peeling.
//
// Why this file is over 500 lines: it still holds every command of the CLI (detect, dump, golden,
// simulate, bench, sweep) and their option definitions. The frame algorithm has left it (the
// detector in core/, the floor in bench/); splitting the commands into one file each, with the
// golden case handling moved into oracle/, is the open remainder of the library issue.
#include "peelcd/core/reference.h"
#include "peelcd/core/aabb.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/bench/peers.h"
#include "peelcd/eval/calibrate.h"
#include "peelcd/eval/classes.h"
#include "peelcd/eval/scenes.h"
#include "peelcd/eval/sweep.h"
#include "peelcd/bench/floor.h"
#include "peelcd/core/cpu_stage.h"
#include "peelcd/core/detector.h"
#include "peelcd/core/options.h"
#include "peelcd/gl/gl_stage.h"
#include "peelcd/version.h"
#include "peelcd/gl_egl/egl_context.h"
#if PEELCD_HAVE_OSMESA
#include "peelcd/gl_osmesa/osmesa_context.h"
#endif
#include "data.h"
#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/output.h"
#include "peelcd/io/result_json.h"
#include "peelcd/io/scene.h"
#include "peelcd/oracle/dump.h"
#include "peelcd/oracle/explain.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>
#include <tuple>
#include <unistd.h>

namespace {

using namespace peelcd;

constexpr int kExitBadInput = 2;

// The default backend: the software reference where it was built, else EGL (a GPU, or Mesa).
#if PEELCD_HAVE_OSMESA
constexpr const char* kDefaultBackend = "osmesa";
#else
constexpr const char* kDefaultBackend = "egl";
#endif

// Output options (--json, --csv, --plot, --out, --report): an empty value is a mistake, refused
// at parse time (exit 2), not read as "no output".
const CLI::Validator kOutputPath(
    [](std::string& value) { return value.empty() ? std::string("an empty path (give a file name, or - for stdout)") : std::string(); },
    "");

// Help that reads as words: CLI11 writes an option's type and each validator joined by ':'
// ("INT:INT in [0 - 64]", "FLOAT:FINITE:FLOAT in [-90 - 90]"); this writes "INT in [0, 64]",
// "FLOAT in [-90, 90]", "INT > 0", "FLOAT >= 0", "{1,2,3}".
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_opts(const CLI::Option* opt) const override {
    std::string s = CLI::Formatter::make_option_opts(opt);
    const auto replace_all = [&](const std::string& from, const std::string& to) {
      for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
    };
    for (const char* type : {"INT", "FLOAT", "UINT"}) {
      const std::string t = type;
      replace_all(t + ":FINITE:" + t + " in ", t + " in ");
      replace_all(t + ":" + t + " in ", t + " in ");
      replace_all(t + ":FINITE", t);
      replace_all(t + ":POSITIVE", t + " > 0");
      replace_all(t + ":NONNEGATIVE", t + " >= 0");
      replace_all(t + ":{", "{");
    }
    // "[0 - 64]" -> "[0, 64]"
    for (std::size_t open = s.find('['); open != std::string::npos; open = s.find('[', open + 1)) {
      const std::size_t close = s.find(']', open), dash = s.find(" - ", open);
      if (close != std::string::npos && dash != std::string::npos && dash < close) s.replace(dash, 3, ", ");
    }
    return s;
  }
};

// A scene's input files: the scene file itself (when there is one) and every mesh it names.
std::vector<std::string> scene_inputs(const Scene& scene) {
  std::vector<std::string> inputs;
  if (std::filesystem::is_regular_file(scene.path)) inputs.push_back(scene.path);
  for (const SceneObject& o : scene.objects) inputs.push_back(o.mesh_path);
  return inputs;
}

// The image stage of a run and the detector over it: GL on OSMesa (the deterministic
// reference) or EGL without a window, or the CPU model (no GL).
struct Runner {
  std::shared_ptr<ImageStage> stage;
  gl::GlImageStage* gl = nullptr;  // the GL stage, or null for the CPU stage
  std::unique_ptr<Detector> detector;

  const std::string& backend() const { return stage->backend(); }
  const std::string& renderer() const { return stage->renderer(); }
  // GL stage options of one configuration (ignored by the CPU stage).
  void use(const gl::GlOptions& options) {
    if (gl) gl->set_options(options);
  }
};

Runner make_runner(const std::string& backend, const gl::GlOptions& options = {}) {
  Runner r;
  std::shared_ptr<gl::Context> context;
#if PEELCD_HAVE_OSMESA
  if (backend == "osmesa") context = std::make_shared<gl::OsmesaContext>();
#endif
  if (backend == "egl") context = std::make_shared<gl::EglContext>();
  if (context) {
    auto stage = std::make_shared<gl::GlImageStage>(context, options);
    r.gl = stage.get();
    r.stage = stage;
  } else if (backend == "cpu") {
    r.stage = std::make_shared<CpuImageStage>();
  } else {
#if !PEELCD_HAVE_OSMESA
    if (backend == "osmesa")
      throw InputError("peelcd: --backend osmesa: this peelcd was built without OSMesa (PEELCD_WITH_OSMESA=OFF): use egl or cpu");
#endif
    throw InputError("peelcd: --backend: unknown backend \"" + backend + "\" (expected osmesa, egl or cpu)");
  }
  r.detector = std::make_unique<Detector>(r.stage);
  return r;
}

struct DetectArgs {
  std::string scene;
  std::vector<std::string> inputs;  // detect: one scene file, or mesh files
  // The frame's options as given on the command line: each row of the option table
  // (peelcd/core/options.h) with a flag, by key; a boolean's "--no-" form as "false".
  std::map<std::string, std::string> options;
  std::map<std::string, bool> flags_on, flags_off;  // boolean rows: --KEY, --no-KEY
  std::string peeler, resolve;  // GL stage options (gl::GlOptions)
  bool paper = false, no_batch = false;
  double max_miss = NAN;  // percent; NaN = report only
  std::string json_out;
  int repeat = 1;
  int views = 0;  // 0 = not given
  bool check = false;
  bool quiet = false;
  bool list = false;    // print every colliding triangle pair (default: the summary only)
  bool status = false;  // exit 1 when nothing collides
  int explain_misses = 0;  // detect --check: explain the first N missed pairs
  std::string backend = kDefaultBackend;
};

// `text` parsed by `parse` (returning std::optional), or an InputError: `unknown` "text"
// (expected `expected`).
template <class Parse>
auto parsed(const std::string& text, Parse parse, const std::string& unknown, const char* expected) {
  const auto m = parse(text);
  if (!m) throw InputError(unknown + " \"" + text + "\" (expected " + expected + ")");
  return *m;
}

// --peeler's value, or an InputError naming it.
Peeler peeler_option(const std::string& text) {
  return parsed(text, parse_peeler, "peelcd: --peeler: unknown peeler", "abuffer or multipass");
}

// GL stage options: the scene file's, overridden by the command line's.
gl::GlOptions merged_gl_options(const Scene& scene, const std::string& peeler, const std::string& resolve,
                               bool no_batch = false) {
  gl::GlOptions o = scene.gl;
  if (no_batch) o.batch = false;
  if (!peeler.empty()) o.peeler = peeler_option(peeler);
  if (!resolve.empty())
    o.resolve = parsed(resolve, parse_resolve, "peelcd: --resolve: unknown resolve", "auto, gpu or host");
  return o;
}

// Command-line values override the scene file's (each checked by the option table's rules, the
// message naming the flag).
DetectOptions merged_options(const Scene& scene, const DetectArgs& a) {
  DetectOptions o = scene.options;
  if (a.paper) {  // the paper's configuration, at the scene's resolution and budget
    const DetectOptions p = paper_options();
    const int res = o.resolution, budget = o.budget;
    o = p;
    o.resolution = res;
    o.budget = budget;
  }
  // --theta/--phi alone turn the paper's frame (roll 0) there, as a scene's "view" does.
  bool direction = false;
  for (const OptionSpec& spec : option_table())
    direction = direction || (sets_view_direction(spec) && a.options.count(spec.key));
  if (direction && !a.options.count("roll")) o.roll = 0.0;
  for (const OptionSpec& spec : option_table()) {
    if (!spec.flag) continue;
    if (spec.kind == OptionSpec::Kind::boolean) {
      const bool on = a.flags_on.count(spec.key) && a.flags_on.at(spec.key);
      const bool off = a.flags_off.count(spec.key) && a.flags_off.at(spec.key);
      if (on && off)
        throw InputError(std::string("peelcd: ") + spec.flag + " and --no-" + (spec.flag + 2) + " contradict each other");
      if (on || off) spec.set(o, OptionValue(on));
      continue;
    }
    const auto given = a.options.find(spec.key);
    if (given == a.options.end()) continue;
    std::string problem;
    const OptionValue value = parse_option(spec, given->second, problem);
    if (!problem.empty()) throw InputError(std::string("peelcd: ") + spec.flag + ": " + problem);
    spec.set(o, value);
  }
  return o;
}

// Writes `text` to `path` through a temporary file and a rename, so a failure never leaves a
// half-written file behind. "-" is stdout.
// --json / --csv outputs: atomic, never destroying (include/peelcd/io/output.h).
void write_output(const std::string& path, const std::string& text) { write_output_file(path, text + "\n", "peelcd: output"); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

// Progress on long work, in one place: a bar redrawn in place on stderr, and one-line phases
// ("loading meshes", "running the frame") cleared when done, only when stderr is a terminal, so
// logs and pipes stay clean. A command that prints a line per step on a terminal stdout (simulate,
// golden compare) asks for the bar only when stdout is redirected (`unless_stdout_tty`).
struct Progress {
  std::string unit;
  bool tty;  // draw at all
  explicit Progress(std::string u = "frames", bool unless_stdout_tty = false)
      : unit(std::move(u)), tty(isatty(STDERR_FILENO) && !(unless_stdout_tty && isatty(STDOUT_FILENO))) {}
  void operator()(std::size_t done, std::size_t total) const {
    if (!tty) return;
    const int width = 40, filled = int(width * done / std::max<std::size_t>(total, 1));
    std::fprintf(stderr, "\r[%s%s] %zu/%zu %s", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), done, total, unit.c_str());
    if (done == total) std::fprintf(stderr, "\n");
  }
  void phase(const std::string& what) const {
    if (tty) std::fprintf(stderr, "\r\033[K%s", what.c_str());
  }
  void clear() const {
    if (tty) std::fprintf(stderr, "\r\033[K");
  }
};

// detect's input: one scene file, or two or more mesh files (identity transforms, default options).
Scene detect_input(const std::vector<std::string>& inputs, const std::string& command = "peelcd detect") {
  const auto is_scene = [](const std::string& p) { return std::filesystem::path(p).extension() == ".json"; };
  if (inputs.size() == 1) {
    if (is_node_scene(inputs[0])) return scene_from_meshes(inputs);  // a glTF scene: one object per node
    if (!is_scene(inputs[0]))
      throw InputError(command + ": '" + inputs[0] + "' is one mesh: give a scene file (.json), a glTF scene (.gltf, .glb) or two or more meshes");
    return load_scene(inputs[0]);
  }
  for (const std::string& p : inputs)
    if (is_scene(p)) throw InputError(command + ": '" + p + "': a scene file (.json) goes alone, not among meshes");
  return scene_from_meshes(inputs);
}

int run_detect(const DetectArgs& a) {
  if (!a.json_out.empty()) check_output_path(a.json_out, "peelcd detect: --json");
  const Progress progress;
  progress.phase("peelcd detect: loading the meshes...");
  const Scene scene = detect_input(a.inputs);
  refuse_overwriting_input(a.json_out, scene_inputs(scene), "peelcd detect: --json");
  const DetectOptions opt = merged_options(scene, a);
  const std::vector<Object> objects = load_objects(scene);
  progress.phase("peelcd detect: running the frame...");

  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.peeler, a.resolve, a.no_batch));
  FrameResult result;
  std::vector<Timings> runs;
  for (int i = 0; i < std::max(1, a.repeat); ++i) {
    result = runner.detector->detect(objects, opt);
    runs.push_back(result.timings);
  }
  progress.clear();
  if (runs.size() > 1) {  // report per-stage medians over the repeated frames
    const auto med = [&](double Timings::*f) {
      std::vector<double> v;
      for (const Timings& t : runs) v.push_back(t.*f);
      return median(v);
    };
    result.timings = {med(&Timings::aabb), med(&Timings::upload), med(&Timings::gpu),
                      med(&Timings::readback), med(&Timings::cpu), med(&Timings::total)};
  }

  // --check: every pair against the exact reference (in the JSON too).
  Score total;
  std::vector<Score> scores;
  std::vector<oracle::PairQuery> misses;  // in frame order, for --explain-misses
  if (a.check)
    for (const PairResult& p : result.pairs) {
      const std::vector<std::uint64_t> exact = exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh);
      scores.push_back(score_contacts(exact, p.colliding));
      if (misses.size() < std::size_t(a.explain_misses))
        for (const std::uint64_t k : exact) {
          const bool reported = std::any_of(p.colliding.begin(), p.colliding.end(), [&](const Contact& c) {
            return c.tri_a == pair_a(k) && c.tri_b == pair_b(k);
          });
          if (!reported && misses.size() < std::size_t(a.explain_misses))
            misses.push_back({p.object_a, p.object_b, pair_a(k), pair_b(k)});
        }
      total.exact += scores.back().exact;
      total.found += scores.back().found;
      total.missed += scores.back().missed;
      total.false_contacts += scores.back().false_contacts;
    }
  // The human summary: on stdout, or on stderr when the JSON goes to stdout.
  FILE* const human = a.json_out == "-" ? stderr : stdout;
  if (!a.quiet) {
    std::fprintf(human, "peelcd detect: %s  (%zu objects, %s, %s)\n", scene.path.c_str(), objects.size(),
                runner.backend().c_str(), result.renderer.c_str());
    if (opt.conservative)
      std::fprintf(human, "conservative  view theta=%g phi=%g roll=%g  views=%d  ids=%s  cull=%s\n", opt.theta, opt.phi, opt.roll,
                  opt.views, to_string(opt.ids), to_string(opt.cull));
    else
      std::fprintf(human, "point sampling  view theta=%g phi=%g roll=%g  views=%d  ids=%s  peel=%s  slope=%g  cull=%s\n", opt.theta,
                  opt.phi, opt.roll, opt.views, to_string(opt.ids), to_string(opt.peel), opt.slope, to_string(opt.cull));
    std::fprintf(human, "stage %s: %zu of %zu ROIs by the exact CPU path, %zu peeled", to_string(opt.stage), result.rois_exact,
                result.pairs.size(), result.pairs.size() - result.rois_exact);
    if (result.views_exhaustive > 0)
      std::fprintf(human, " (%zu views fell back to the exhaustive exact test: k-buffer too deep or too large)",
                   result.views_exhaustive);
    std::fprintf(human, "\n");
    if (result.pairs.empty()) std::fprintf(human, "no overlapping bounding boxes: no GL work\n");
    std::size_t colliding = 0, colliding_objects = 0;
    for (const PairResult& p : result.pairs) {
      colliding += p.colliding.size();
      colliding_objects += p.colliding.empty() ? 0 : 1;
      if (p.exact_stage) {
        std::fprintf(human, "%s x %s: exact CPU path (predicted %.3f ms; image stage %.3f ms), %zu+%zu tris in the ROI, "
                    "%zu candidates, %zu colliding\n",
                    objects[p.object_a].name.c_str(), objects[p.object_b].name.c_str(), p.predicted_exact_ms,
                    p.predicted_image_ms, p.triangles_in_roi_a, p.triangles_in_roi_b, p.candidates, p.colliding.size());
      } else {
        std::fprintf(human, "%s x %s: ROI %dx%d, eps %.3g, drawn %zu+%zu of %zu+%zu tris, %d layers, %zu PCS, %zu candidates, %zu colliding\n",
                    objects[p.object_a].name.c_str(), objects[p.object_b].name.c_str(), p.resolution,
                    p.resolution, p.epsilon, p.triangles_drawn_a, p.triangles_drawn_b, p.triangles_in_roi_a,
                    p.triangles_in_roi_b, p.layers,
                    p.pcs_count, p.candidates, p.colliding.size());
        if (p.views_exhaustive > 0)  // a fallback is never silent
          std::fprintf(human, "  path %s: %s\n", pair_path(p), pair_path_reason(p, opt).c_str());
      }
      if (a.check) {
        const Score& sc = scores[std::size_t(&p - result.pairs.data())];
        std::fprintf(human, "  exact reference: %zu pairs; found %zu, missed %zu (miss ratio %.2f%%), false contacts %zu\n",
                    sc.exact, sc.found, sc.missed, 100.0 * sc.miss_ratio(), sc.false_contacts);
      }
    }
    std::fprintf(human, "%s: %zu colliding triangle pairs in %zu of %zu overlapping object pairs%s\n",
                 colliding ? "collision" : "no collision", colliding, colliding_objects, result.pairs.size(),
                 colliding && !a.list ? " (--list prints them)" : "");
    if (a.list)
      for (const PairResult& p : result.pairs) {
        if (p.colliding.empty()) continue;
        std::fprintf(human, "%s x %s: triangle pairs (%s, %s)\n", objects[p.object_a].name.c_str(),
                     objects[p.object_b].name.c_str(), objects[p.object_a].name.c_str(), objects[p.object_b].name.c_str());
        std::string line = " ";
        for (const Contact& c : p.colliding) {
          line += " (" + std::to_string(c.tri_a) + "," + std::to_string(c.tri_b) + ")";
          if (line.size() > 90) {
            std::fprintf(human, "%s\n", line.c_str());
            line = " ";
          }
        }
        if (line.size() > 1) std::fprintf(human, "%s\n", line.c_str());
      }
    const Timings& t = result.timings;
    std::fprintf(human, "timings (ms%s): aabb %.3f  upload %.3f  gpu %.3f  readback %.3f  cpu %.3f  total %.3f\n",
                runs.size() > 1 ? (", median of " + std::to_string(runs.size())).c_str() : "",
                t.aabb, t.upload, t.gpu, t.readback, t.cpu, t.total);
  }
  if (!a.json_out.empty()) write_output(a.json_out, to_json(result, objects, opt, a.check ? &scores : nullptr).dump(2));
  if (a.check && !a.quiet)
    std::fprintf(human, "check: %zu exact pairs, %zu missed (miss ratio %.4f%%)\n", total.exact, total.missed,
                100.0 * total.miss_ratio());
  if (!misses.empty()) {  // --explain-misses: the same frame again, every layer captured
    const oracle::FrameTrace trace(*runner.detector, objects, opt);
    std::fprintf(human, "explain: the first %zu missed pair(s) (peelcd explain ... --pair A:TRI,B:TRI for the whole walk)\n",
                 misses.size());
    for (const oracle::PairQuery& m : misses)
      std::fprintf(human, "  %s:%u,%s:%u: %s\n", objects[m.object_a].name.c_str(), m.tri_a,
                   objects[m.object_b].name.c_str(), m.tri_b, trace.explain(m).verdict_line.c_str());
  }
  if (a.check && !std::isnan(a.max_miss) && 100.0 * total.miss_ratio() > a.max_miss) {
    std::fprintf(stderr, "peelcd detect: miss ratio %.4f%% is above --max-miss %g%%\n", 100.0 * total.miss_ratio(),
                 a.max_miss);
    return 3;
  }
  if (a.status) {  // for scripts, as grep: 0 when something collides, 1 when nothing does
    bool any = false;
    for (const PairResult& p : result.pairs) any = any || !p.colliding.empty();
    return any ? 0 : 1;
  }
  return 0;
}

struct ExplainArgs {
  std::string pair;  // OBJ_A:TRI_A,OBJ_B:TRI_B
  std::string out;   // the page's folder
};

// peelcd explain: why one triangle pair was found or missed (peelcd/oracle/explain.h).
int run_explain(const DetectArgs& a, const ExplainArgs& x) {
  if (!a.json_out.empty()) check_output_path(a.json_out, "peelcd explain: --json");
  if (!x.out.empty()) {
    const std::filesystem::path out(x.out);
    if (std::filesystem::exists(out) && !(std::filesystem::is_directory(out) && std::filesystem::is_empty(out)))
      throw InputError("peelcd explain: --out '" + x.out + "' exists and is not an empty folder");
    if (!out.parent_path().empty() && !std::filesystem::is_directory(out.parent_path()))
      throw InputError("peelcd explain: --out '" + x.out + "': the parent folder does not exist");
  }
  const Progress progress;
  progress.phase("peelcd explain: loading the meshes...");
  const Scene scene = detect_input(a.inputs, "peelcd explain");
  refuse_overwriting_input(a.json_out, scene_inputs(scene), "peelcd explain: --json");
  const DetectOptions opt = merged_options(scene, a);
  const std::vector<Object> objects = load_objects(scene);
  const oracle::PairQuery query = oracle::parse_pair_query(x.pair, objects);
  progress.phase("peelcd explain: running the frame...");
  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.peeler, a.resolve, a.no_batch));
  const oracle::FrameTrace trace(*runner.detector, objects, opt);
  const oracle::Explanation e = trace.explain(query);
  progress.clear();
  FILE* const human = a.json_out == "-" ? stderr : stdout;
  if (!a.quiet) std::fputs(oracle::explain_text(e).c_str(), human);
  if (!a.json_out.empty()) write_output(a.json_out, oracle::to_json(e).dump(2));
  if (!x.out.empty()) {
    oracle::write_explain_page(e, x.out);
    if (!a.quiet) std::fprintf(human, "page: %s/index.html\n", x.out.c_str());
  }
  return 0;
}

// One frame with every layer captured: the dump of `scene` under `opt` on `backend`.
// Dumps check the image stage: every ROI is peeled (Stage::image), whatever the router would do.
oracle::Dump capture_frame(const std::vector<Object>& objects, const DetectOptions& options, Runner& runner) {
  std::vector<CapturedView> captured;
  DetectOptions opt = options;
  opt.stage = Stage::image;
  runner.detector->capture_layers(&captured);
  FrameResult result;
  try {
    result = runner.detector->detect(objects, opt);
  } catch (...) {
    runner.detector->capture_layers(nullptr);
    throw;
  }
  runner.detector->capture_layers(nullptr);
  return oracle::make_dump(result, captured, objects, opt, runner.stage->renderer(), runner.stage->version(),
                           runner.backend());
}

// The broad phase's overlapping object pairs: the ROIs of a frame (before culling).
std::size_t count_overlapping_pairs(const std::vector<Object>& objects) {
  std::vector<Aabb> boxes;
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  return overlapping_pairs(boxes).size();
}

struct DumpArgs {
  std::string out;
  std::string pair;        // "A,B": only that pair's ROI
  std::size_t max_rois = 64;  // refuse larger dumps unless raised
};

int run_dump(const DetectArgs& a, const DumpArgs& d) {
  const Progress progress;
  progress.phase("peelcd dump: loading the meshes...");
  const Scene scene = detect_input(a.inputs, "peelcd dump");
  const DetectOptions opt = merged_options(scene, a);
  std::vector<Object> objects = load_objects(scene);
  // Refused before any work: an output that exists and is not an empty folder.
  if (std::filesystem::exists(d.out) &&
      !(std::filesystem::is_directory(d.out) && std::filesystem::is_empty(d.out)))
    throw InputError("peelcd dump: --out '" + d.out + "' exists and is not an empty folder");
  {
    const std::filesystem::path parent = std::filesystem::path(d.out).parent_path();
    if (!parent.empty() && !std::filesystem::is_directory(parent))
      throw InputError("peelcd dump: --out '" + d.out + "': the folder '" + parent.string() + "' does not exist");
    if (access(parent.empty() ? "." : parent.c_str(), W_OK | X_OK) != 0)
      throw InputError("peelcd dump: --out '" + d.out + "': cannot write into the folder '" +
                       (parent.empty() ? std::string(".") : parent.string()) + "'");
  }
  std::vector<std::size_t> original;  // object indices in the scene, for --pair
  if (!d.pair.empty()) {
    const std::size_t comma = d.pair.find(',');
    if (comma == std::string::npos || comma == 0 || comma + 1 == d.pair.size())
      throw InputError("peelcd dump: --pair \"" + d.pair + "\": expected two object names, A,B");
    const std::string names[2] = {d.pair.substr(0, comma), d.pair.substr(comma + 1)};
    std::vector<Object> two;
    for (const std::string& name : names) {
      std::size_t found = objects.size();
      for (std::size_t i = 0; i < objects.size(); ++i)
        if (objects[i].name == name) found = i;
      if (found == objects.size())
        throw InputError("peelcd dump: --pair: no object named \"" + name + "\" in " + scene.path);
      original.push_back(found);
    }
    if (original[0] == original[1]) throw InputError("peelcd dump: --pair names one object twice");
    if (original[0] > original[1]) std::swap(original[0], original[1]);  // scene order, as detect pairs them
    two.push_back(objects[original[0]]);
    two.push_back(objects[original[1]]);
    objects = std::move(two);
  }
  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.peeler, a.resolve, a.no_batch));
  // The cap is checked on the broad phase's ROIs before any layer is captured.
  {
    const std::size_t rois = count_overlapping_pairs(objects);
    if (rois > d.max_rois)
      throw InputError("peelcd dump: " + scene.path + " has " + std::to_string(rois) +
                       " overlapping pairs (ROIs), above --max-rois " + std::to_string(d.max_rois) +
                       ": dump one with --pair A,B, or raise --max-rois");
  }
  progress.phase("peelcd dump: peeling and reading every layer back...");
  oracle::Dump dump = capture_frame(objects, opt, runner);
  progress.phase("peelcd dump: writing the layers...");
  if (!original.empty())
    for (auto& p : dump.pairs) p.object_a = original[p.object_a], p.object_b = original[p.object_b];
  if (!d.pair.empty() && dump.pairs.empty() && !a.quiet)
    std::fprintf(stderr, "peelcd dump: %s and %s do not overlap: the dump has no ROI\n", objects[0].name.c_str(),
                 objects[1].name.c_str());
  {
    const DeferSignals hold;  // Ctrl-C while writing: the dump completes (or is removed), then exit
    oracle::write_dump(dump, d.out, true);
  }
  progress.clear();
  std::size_t layers = 0, views = 0;
  for (const auto& p : dump.pairs)
    for (const auto& v : p.views) layers += v.layers.size(), ++views;
  if (!a.quiet)
    std::printf("peelcd dump: %s -> %s: %zu ROIs, %zu views, %zu layers (%s); open %s/index.html\n",
                scene.path.c_str(), d.out.c_str(), dump.pairs.size(), views, layers, dump.renderer.c_str(), d.out.c_str());
  return 0;
}

struct GoldenArgs {
  std::vector<std::string> cases;  // empty = every case
  std::string dir;  // empty: the installed or source tree's fixtures/golden (data_dir())
  std::string backend = kDefaultBackend;
  std::string tier = "auto";
  std::string report = "golden-report";
  std::string peeler;  // empty: the case's (the default)
  std::string resolve;  // empty: the default (auto)
  std::string require_renderer;  // skip (exit 77) unless GL_RENDERER contains this
  std::string shard;             // "K/N": every N-th case from the K-th
  int repeat = 1;
};

// ctest's SKIP_RETURN_CODE for a run that cannot take place here (the reason on stderr).
constexpr int kExitSkipped = 77;

std::vector<std::string> golden_cases(const GoldenArgs& a) {
  if (!a.cases.empty()) return a.cases;
  std::vector<std::string> all;
  if (!std::filesystem::is_directory(a.dir)) throw InputError("peelcd golden: '" + a.dir + "' is not a folder");
  for (const auto& e : std::filesystem::directory_iterator(a.dir))
    if (std::filesystem::exists(e.path() / "case.json")) all.push_back(e.path().filename().string());
  std::sort(all.begin(), all.end());
  if (all.empty()) throw InputError("peelcd golden: no cases (folders with a case.json) in '" + a.dir + "'");
  return all;
}

std::string case_scene(const GoldenArgs& a, const std::string& name) {
  const std::string path = a.dir + "/" + name + "/case.json";
  if (!std::filesystem::exists(path)) throw InputError("peelcd golden: unknown case \"" + name + "\" (no " + path + ")");
  return path;
}

int run_golden_record(const GoldenArgs& a) {
  // Goldens come from the reference backend only.
  Runner runner = make_runner("osmesa");
  for (const std::string& name : golden_cases(a)) {
    const Scene scene = load_scene(case_scene(a, name));
    const std::vector<Object> objects = load_objects(scene);
    runner.use(scene.gl);
    const oracle::Dump dump = capture_frame(objects, scene.options, runner);
    const std::string dir = a.dir + "/" + name + "/expected", fresh = dir + ".new";
    std::error_code ec;
    const DeferSignals hold;  // Ctrl-C: this case's goldens are replaced whole, or not at all
    std::filesystem::remove_all(fresh, ec);
    oracle::write_dump(dump, fresh, false);
    std::filesystem::remove_all(dir);
    std::filesystem::rename(fresh, dir);
    std::size_t layers = 0;
    for (const auto& p : dump.pairs)
      for (const auto& v : p.views) layers += v.layers.size();
    std::printf("recorded %s: %zu ROIs, %zu layers -> %s\n", name.c_str(), dump.pairs.size(), layers, dir.c_str());
  }
  return 0;
}

std::pair<std::size_t, std::size_t> parse_shard(const std::string& text, const std::string& what);

int run_golden_compare(const GoldenArgs& a) {
  Runner runner = make_runner(a.backend);
  const std::string renderer = runner.renderer();
  if (!a.require_renderer.empty() && renderer.find(a.require_renderer) == std::string::npos) {
    std::fprintf(stderr, "peelcd golden compare: skipped: the renderer is \"%s\", not %s (--require-renderer)\n",
                 renderer.c_str(), a.require_renderer.c_str());
    return kExitSkipped;
  }
  oracle::Tier tier = renderer.find("llvmpipe") != std::string::npos ? oracle::Tier::exact : oracle::Tier::hardware;
  if (a.tier == "exact") tier = oracle::Tier::exact;
  else if (a.tier == "hardware") tier = oracle::Tier::hardware;
  else if (a.tier != "auto") throw InputError("peelcd golden compare: --tier: unknown tier \"" + a.tier + "\" (expected auto, exact or hardware)");
  std::printf("golden compare: backend %s, %s, %s tier\n", runner.backend().c_str(), renderer.c_str(),
              oracle::to_string(tier));
  int failed = 0;
  const auto [shard, shards] = parse_shard(a.shard, "peelcd golden compare:");
  const std::vector<std::string> all_cases = golden_cases(a);
  std::vector<std::string> cases;
  for (std::size_t i = 0; i < all_cases.size(); ++i)
    if (i % shards == shard) cases.push_back(all_cases[i]);
  if (shards > 1) std::printf("golden compare: shard %zu/%zu: %zu of %zu cases\n", shard + 1, shards, cases.size(), all_cases.size());
  const Progress progress("cases", true);
  std::size_t done = 0;
  for (const std::string& name : cases) {
    progress(done++, cases.size());
    Scene scene = load_scene(case_scene(a, name));
    runner.use(merged_gl_options(scene, a.peeler, a.resolve));
    const std::vector<Object> objects = load_objects(scene);
    const oracle::Dump expected = oracle::read_dump(a.dir + "/" + name + "/expected");
    for (int run = 0; run < std::max(1, a.repeat); ++run) {
      const oracle::Dump actual = capture_frame(objects, scene.options, runner);
      const oracle::Comparison c = oracle::compare_dumps(expected, actual, tier);
      const std::string label = a.repeat > 1 ? name + " (run " + std::to_string(run + 1) + ")" : name;
      if (c.ok()) {
        std::printf("%s", oracle::report_text(c, label, tier).c_str());
        continue;
      }
      ++failed;
      std::printf("%s", oracle::write_report(expected, actual, c, label, a.report + "/" + name).c_str());
      break;
    }
  }
  progress(cases.size(), cases.size());
  std::printf("golden compare: %d case(s) differ\n", failed);
  return failed ? 1 : 0;
}

// Two dumps from any producers (docs/dump-format.md), compared under a tier.
struct CompareDumpsArgs {
  std::string expected, actual, tier = "exact", report = "golden-report";
};

int run_compare_dumps(const CompareDumpsArgs& a) {
  oracle::Tier tier = oracle::Tier::exact;
  if (a.tier == "hardware") tier = oracle::Tier::hardware;
  else if (a.tier != "exact")
    throw InputError("peelcd golden compare-dumps: --tier: unknown tier \"" + a.tier + "\" (expected exact or hardware)");
  const oracle::Dump expected = oracle::read_dump(a.expected);
  const oracle::Dump actual = oracle::read_dump(a.actual);
  const oracle::Comparison c = oracle::compare_dumps(expected, actual, tier);
  const std::string label = a.expected + " vs " + a.actual;
  if (c.ok()) {
    std::printf("%s", oracle::report_text(c, label, tier).c_str());
    return 0;
  }
  std::printf("%s", oracle::write_report(expected, actual, c, label, a.report).c_str());
  return 1;
}

// ---- dynamic scenes and benchmarks ----

std::unique_ptr<Sequence> make_sequence(const std::string& name, std::size_t frames, bool rigid = true,
                                        std::size_t objects = 200) {
  if (name == "test1") return make_test1(cli::data_dir("fixtures/meshes"), frames, rigid);
  if (name == "test2") return make_test2(cli::data_dir("fixtures/meshes"), frames, rigid);
  if (name == "crowd") return make_crowd(objects, frames, rigid);
  throw InputError("peelcd: unknown test scene \"" + name + "\" (expected test1, test2 or crowd)");
}

// The paper's Tables 1 and 2 (GeForce 7900GTX): nCTP, AABB, GPU, readback, CPU, total per phase.
const std::vector<std::array<double, 6>>& paper_table(const std::string& name) {
  static const std::vector<std::array<double, 6>> t1 = {{15, 0.07, 3.11, 0.11, 0.07, 3.36},
                                                         {33, 0.07, 3.08, 0.13, 0.14, 3.42},
                                                         {96, 0.07, 3.28, 0.15, 0.44, 3.94},
                                                         {173, 0.07, 3.02, 0.36, 0.68, 4.13}};
  static const std::vector<std::array<double, 6>> t2 = {
      {16, 0.03, 2.66, 0.12, 0.10, 2.91},  {115, 0.03, 3.05, 0.68, 0.66, 4.42}, {96, 0.03, 4.26, 0.39, 0.48, 5.16},
      {39, 0.03, 2.39, 0.14, 0.36, 2.93},  {125, 0.03, 3.22, 0.73, 0.67, 4.65}, {222, 0.03, 2.38, 0.84, 0.95, 4.20},
      {339, 0.03, 3.15, 0.92, 1.66, 5.75}, {262, 0.03, 2.90, 0.71, 1.17, 4.81}};
  return name == "test1" ? t1 : t2;
}

// Found, missed and false contacts of a frame against the exact pairs of the CGAL peer.
Score score_frame(const FrameResult& r, const bench::PeerFrame& exact) {
  Score total;
  for (std::size_t i = 0; i < exact.objects.size(); ++i) {
    std::vector<Contact> none;
    const std::vector<Contact>* found = &none;
    for (const PairResult& p : r.pairs)
      if (p.object_a == exact.objects[i].first && p.object_b == exact.objects[i].second) found = &p.colliding;
    const Score s = score_contacts(exact.per_pair[i], *found);
    total.exact += s.exact;
    total.found += s.found;
    total.missed += s.missed;
    total.false_contacts += s.false_contacts;
  }
  return total;
}

struct SimArgs {
  std::string test;
  std::size_t frames = 40;
  std::size_t objects = 200;  // crowd
  bool no_rigid = false;
  DetectArgs detect;
  std::string csv;
};

int run_simulate(const SimArgs& a) {
  if (!a.csv.empty()) check_output_path(a.csv, "peelcd simulate: --csv");
  const auto seq = make_sequence(a.test, a.frames, !a.no_rigid, a.objects);
  Scene defaults;
  const DetectOptions opt = merged_options(defaults, a.detect);
  Runner runner = make_runner(a.detect.backend, merged_gl_options(Scene{}, a.detect.peeler, a.detect.resolve, a.detect.no_batch));
  std::vector<Object> objects;
  std::string csv = "frame,phase,triangles,rois,rois_exact,rois_peeled,triangles_uploaded,triangles_indexed,shape_uploads,gl_passes,pcs_readbacks,nctp,found,"
                    "false_contacts,aabb_ms,upload_ms,gpu_ms,readback_ms,cpu_ms,total_ms\n";
  std::printf("peelcd simulate %s: %zu frames, %s, ids=%s peel=%s slope=%g views=%d res=%s\n", seq->name().c_str(),
              seq->frames(), runner.renderer().c_str(), to_string(opt.ids), to_string(opt.peel), opt.slope,
              opt.views, opt.resolution ? std::to_string(opt.resolution).c_str() : ("budget " + std::to_string(opt.budget)).c_str());
  std::printf("%5s %5s %7s %5s %5s %6s %8s %8s %6s %6s %5s %6s %6s %6s %5s %7s %8s %8s %8s %8s\n", "frame", "phase",
              "tris", "ROIs", "exact", "peeled", "uploaded", "indexed", "shapes", "passes", "reads", "nCTP", "found", "miss%",
              "false", "aabb", "gpu", "readback", "cpu", "total");
  struct PhaseSum {
    std::size_t frames = 0;
    double nctp = 0, found = 0, aabb = 0, gpu = 0, readback = 0, cpu = 0, total = 0;
  };
  std::vector<PhaseSum> phases(seq->phases());
  std::size_t false_total = 0;
  FrameResult r;  // reused frame after frame, as an application would
  const Progress progress("frames", true);
  for (std::size_t f = 0; f < seq->frames(); ++f) {
    progress(f, seq->frames());
    seq->frame(f, objects);
    runner.detector->detect(objects, opt, r);
    const bench::PeerFrame exact = bench::cgal_frame(objects);
    const Score sc = score_frame(r, exact);
    false_total += sc.false_contacts;
    std::size_t tris = 0;
    for (const Object& o : objects) tris += o.mesh.triangles.size();
    const Timings& t = r.timings;
    const int ph = seq->phase(f);
    std::printf("%5zu %5c %7zu %5zu %5zu %6zu %8zu %8zu %6zu %6zu %5zu %6zu %6zu %5.1f%% %5zu %7.3f %8.2f %8.3f %8.2f %8.2f\n",
                f, char('a' + ph), tris, r.pairs.size(), r.rois_exact, r.rois_peeled, r.triangles_uploaded, r.triangles_indexed,
                r.shape_uploads, r.gl_passes, r.pcs_readbacks, sc.exact, sc.found, 100.0 * sc.miss_ratio(), sc.false_contacts, t.aabb,
                t.upload + t.gpu, t.readback, t.cpu, t.total);
    char line[512];
    std::snprintf(line, sizeof line, "%zu,%c,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", f,
                  char('a' + ph), tris, r.pairs.size(), r.rois_exact, r.rois_peeled, r.triangles_uploaded, r.triangles_indexed,
                  r.shape_uploads, r.gl_passes,
                  r.pcs_readbacks, sc.exact, sc.found, sc.false_contacts, t.aabb, t.upload, t.gpu, t.readback, t.cpu,
                  t.total);
    csv += line;
    PhaseSum& p = phases[ph];
    ++p.frames;
    p.nctp += double(sc.exact);
    p.found += double(sc.found);
    p.aabb += t.aabb;
    p.gpu += t.upload + t.gpu;
    p.readback += t.readback;
    p.cpu += t.cpu;
    p.total += t.total;
  }
  progress(seq->frames(), seq->frames());
  const bool paper_scene = seq->name() == "test1" || seq->name() == "test2";
  std::printf(paper_scene ? "\nsummary (means per phase; the paper's table beside, GeForce 7900GTX; ms)\n"
                          : "\nsummary (means; ms)\n");
  std::printf("%5s | %6s %6s %6s %7s %8s %7s %8s", "", "nCTP", "found", "AABB", "GPU", "readback", "CPU", "total");
  if (paper_scene) std::printf(" | %6s %6s %6s %8s %6s %6s", "nCTP", "AABB", "GPU", "readback", "CPU", "total");
  std::printf("\n");
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const PhaseSum& p = phases[i];
    const double n = std::max<double>(1, double(p.frames));
    std::printf("(%c)   | %6.0f %6.0f %6.3f %7.2f %8.3f %7.2f %8.2f", char('a' + i), p.nctp / n, p.found / n, p.aabb / n,
                p.gpu / n, p.readback / n, p.cpu / n, p.total / n);
    if (paper_scene) {
      const auto& paper = paper_table(seq->name());
      std::printf(" | %6.0f %6.2f %6.2f %8.2f %6.2f %6.2f", paper[i][0], paper[i][1], paper[i][2], paper[i][3], paper[i][4],
                  paper[i][5]);
    }
    std::printf("\n");
  }
  std::printf("false contacts over all frames: %zu\n", false_total);
  if (!a.csv.empty()) write_output(a.csv, csv);
  return false_total ? 1 : 0;
}

struct BenchArgs {
  std::string scene = "test1";  // test1, test2, crowd or a scene file
  std::size_t frames = 12;
  std::size_t objects = 200;  // crowd
  int res = 0;  // 0: the shared 512^2 budget, tiles by need (detect's default)
  std::string backend = kDefaultBackend;
  unsigned threads = 0;  // 0: the machine's (at most 8)
  std::string csv;
};

// Found, missed and false contacts of a peer against the exact pairs, object pair by object pair
// (the peers' broad phases may list pairs in another order, or more of them).
Score score_peer(const bench::PeerFrame& exact, const bench::PeerFrame& peer) {
  Score total;
  for (std::size_t i = 0; i < exact.objects.size(); ++i) {
    const auto it = std::lower_bound(peer.objects.begin(), peer.objects.end(), exact.objects[i]);
    static const std::vector<std::uint64_t> none;
    const std::vector<std::uint64_t>& got =
        it != peer.objects.end() && *it == exact.objects[i] ? peer.per_pair[std::size_t(it - peer.objects.begin())] : none;
    std::vector<std::uint64_t> common;
    std::set_intersection(exact.per_pair[i].begin(), exact.per_pair[i].end(), got.begin(), got.end(),
                          std::back_inserter(common));
    total.exact += exact.per_pair[i].size();
    total.found += common.size();
    total.missed += exact.per_pair[i].size() - common.size();
    total.false_contacts += got.size() - common.size();
  }
  // Pairs the peer reported that the exact broad phase does not list: all false.
  for (std::size_t j = 0; j < peer.objects.size(); ++j)
    if (!std::binary_search(exact.objects.begin(), exact.objects.end(), peer.objects[j]))
      total.false_contacts += peer.per_pair[j].size();
  return total;
}

int run_bench(const BenchArgs& a) {
  if (!a.csv.empty()) check_output_path(a.csv, "peelcd bench: --csv");
  std::unique_ptr<Sequence> seq;
  std::vector<Object> fixed;
  if (a.scene == "test1" || a.scene == "test2") {
    seq = make_sequence(a.scene, a.frames);
  } else if (a.scene == "crowd") {
    seq = make_crowd(a.objects, a.frames);
  } else {
    // A scene file's objects do not move: passed as rigid at the identity pose, so that every
    // method may keep what it builds from them (FCL its trees, the GL stage the shapes).
    fixed = load_objects(load_scene(a.scene));
    for (Object& o : fixed) o.rigid = RigidMotion{std::make_shared<const Mesh>(o.mesh), Eigen::Affine3d::Identity()};
  }
  const unsigned hw = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  const unsigned threads = a.threads ? a.threads : hw;
  // llvmpipe reads its thread count when the context is made: the same count as the peers. One
  // thread is LP_NUM_THREADS=0: llvmpipe rasterizes on the calling thread (with 1 it hands every
  // draw to one worker thread and waits for it: still one thread working, plus the handoff).
  if (a.threads) setenv("LP_NUM_THREADS", std::to_string(a.threads == 1 ? 0 : a.threads).c_str(), 1);
  gl::GlOptions gl_base;
  gl_base.workers = threads;
  Runner runner = make_runner(a.backend, gl_base);
  if (!runner.gl) throw InputError("peelcd bench: --backend cpu: the benchmark times GL stages (use osmesa or egl)");
  if (a.res > 0 && a.res > runner.stage->max_resolution())
    throw InputError("peelcd bench: --res " + std::to_string(a.res) + " is above GL_MAX_TEXTURE_SIZE");

  struct Config {
    std::string name;
    std::string column;  // its column in the per-phase table
    DetectOptions opt;
    gl::GlOptions gl;
  };
  std::vector<Config> configs;
  DetectOptions base;  // the default of detect: the router
  base.threads = threads;  // culling and the exact CPU path: the peers' thread count
  base.resolution = a.res;
  gl::GlOptions gpu_resolve = gl_base;
  gpu_resolve.resolve = Resolve::gpu;
  gl::GlOptions multi = gl_base;
  multi.peeler = Peeler::multipass;
  configs.push_back({"peelcd default (stage auto)", "default", base, gl_base});
  DetectOptions exact = base;
  exact.stage = Stage::exact;
  configs.push_back({"peelcd exact CPU path (no image)", "exact", exact, gl_base});
  DetectOptions image = base;
  image.stage = Stage::image;
  configs.push_back({"peelcd image stage (conservative)", "image", image, gl_base});
  DetectOptions box = image;
  box.cull = Cull::box;
  configs.push_back({"peelcd image stage, box culling", "box cull", box, gl_base});
  configs.push_back({"peelcd image stage, GPU resolve", "gpu rslv", image, gpu_resolve});
  DetectOptions half = image;  // half the tile side: the texels culling saves
  if (half.resolution > 0)
    half.resolution = std::max(16, half.resolution / 2);
  else
    half.budget = std::max(16, half.budget / 2);
  configs.push_back({"peelcd image stage, half resolution", "half res", half, gl_base});
  if (image.resolution == 0) {  // the conservative stage's earlier tiles: 12 texels per median edge
    DetectOptions fine = image;
    fine.edge_texels = kPointEdgeTexels;
    configs.push_back({"peelcd image stage, 12 texels per edge", "12 tx/edge", fine, gl_base});
  }
  // Point sampling (the paper's image stage, with this project's culling, views and slope
  // epsilon): the default of 0.2.0, three views along the world axes. Lossy: see the miss column.
  DetectOptions point = image;
  point.conservative = false;
  point.ids = IdMode::ring;
  point.theta = point.phi = point.roll = 0.0;
  point.views = 3;
  configs.push_back({"peelcd point sampling, 3 views", "point 3v", point, gl_base});
  configs.push_back({"peelcd point sampling, multi-pass", "multipass", point, multi});
  DetectOptions one = point;
  one.views = 1;
  configs.push_back({"peelcd point, 1 view, full peeling", "1v full", one, gl_base});
  DetectOptions paper = one;  // the paper's pipeline: the whole overlap box, one view
  paper.peel = PeelMode::alternate;
  paper.ids = IdMode::paper;
  paper.slope = 0.0;
  paper.cull = Cull::box;
  if (a.res == 0 && !seq) paper.resolution = 256;  // the paper's 256^2 on one pair (its Fig. 8)
  configs.push_back({"peelcd paper config", "paper", paper, gl_base});
  configs.push_back({"peelcd paper config, multi-pass", "paper mp", paper, multi});

  // The floors: one bare draw of every triangle touching the overlap box (the paper's ROI), and
  // of the triangles contact culling keeps (what the image-stage configurations draw).
  DetectOptions floor1 = point, cfloor1 = point;
  floor1.views = cfloor1.views = 1;
  floor1.cull = Cull::box;
  cfloor1.cull = Cull::contact;
  cfloor1.edge_texels = edge_texels_of(image);  // the conservative image stage's tiles
  const std::size_t cg = configs.size(), fr = cg + 1, fb = cg + 2, fl = cg + 3, cfl = cg + 4;
  const std::size_t methods = cg + 5;
  std::vector<std::string> names;
  for (const Config& c : configs) names.push_back(c.name);
  names.insert(names.end(), {"CGAL, cropped to the overlap box", "FCL 0.7, deforming refit",
                             "FCL 0.7, deforming rebuilt cropped", "floor: 1 bare draw, overlap box",
                             "floor: 1 bare draw, culled"});
  bench::FclPeer fcl_refit(bench::FclPeer::Deforming::refit, threads);
  bench::FclPeer fcl_rebuild(bench::FclPeer::Deforming::rebuild, threads);
  std::vector<FrameResult> results(configs.size());
  std::vector<std::vector<double>> ms(methods);
  std::vector<Score> scores(methods);
  std::vector<std::vector<std::vector<double>>> phase_ms;  // [phase][method] -> frame times
  if (seq) phase_ms.assign(seq->phases(), std::vector<std::vector<double>>(methods));
  std::string csv = "peelcd_version,frame,method,ms,nctp,found,false_contacts\n";
  std::vector<Object> objects;
  const std::size_t frames = seq ? seq->frames() : a.frames;
  // One untimed pass over the frames first: shader compilation, rigid shapes' uploads, FCL's
  // trees of rigid shapes and the growth of every buffer happen once, and would otherwise land
  // on whichever method meets them first. The timed pass is the steady state.
  for (std::size_t f = 0; f < (seq ? frames : std::min<std::size_t>(frames, 1)); ++f) {
    if (seq) seq->frame(f, objects);
    const std::vector<Object>& obj = seq ? objects : fixed;
    for (std::size_t c = 0; c < configs.size(); ++c) {
      runner.use(configs[c].gl);
      runner.detector->detect(obj, configs[c].opt, results[c]);
    }
    fcl_refit.frame(obj);
    fcl_rebuild.frame(obj);
  }
  std::size_t rois = 0, rois_routed_exact = 0;
  Progress progress;
  for (std::size_t f = 0; f < frames; ++f) {
    if (seq) seq->frame(f, objects);
    const std::vector<Object>& obj = seq ? objects : fixed;
    // Side by side on the same frame: the exact reference first (it is the CGAL peer).
    const bench::PeerFrame ref = bench::cgal_frame(obj, threads);
    std::vector<double> t(methods);
    std::vector<Score> s(methods);
    for (std::size_t c = 0; c < configs.size(); ++c) {
      runner.use(configs[c].gl);
      runner.detector->detect(obj, configs[c].opt, results[c]);
      t[c] = results[c].timings.total;
      s[c] = score_frame(results[c], ref);
    }
    rois += results[0].pairs.size();
    rois_routed_exact += results[0].rois_exact;
    t[cg] = ref.ms;
    s[cg] = Score{ref.pairs, ref.pairs, 0, 0};
    const bench::PeerFrame refit = fcl_refit.frame(obj);
    t[fr] = refit.ms;
    s[fr] = score_peer(ref, refit);
    const bench::PeerFrame rebuilt = fcl_rebuild.frame(obj);
    t[fb] = rebuilt.ms;
    s[fb] = score_peer(ref, rebuilt);
    runner.use(gl_base);
    t[fl] = bench::floor_ms(*runner.detector, *runner.gl, obj, floor1);
    t[cfl] = bench::floor_ms(*runner.detector, *runner.gl, obj, cfloor1);
    s[fl] = s[cfl] = Score{ref.pairs, 0, ref.pairs, 0};
    for (std::size_t m = 0; m < methods; ++m) {
      ms[m].push_back(t[m]);
      scores[m].exact += s[m].exact;
      scores[m].found += s[m].found;
      scores[m].missed += s[m].missed;
      scores[m].false_contacts += s[m].false_contacts;
      if (seq) phase_ms[seq->phase(f)][m].push_back(t[m]);
      char line[256];
      std::snprintf(line, sizeof line, "%s,%zu,\"%s\",%.4f,%zu,%zu,%zu\n", PEELCD_VERSION_STRING, f, names[m].c_str(), t[m],
                    s[m].exact, s[m].found, s[m].false_contacts);
      csv += line;
    }
    progress(f + 1, frames);
  }
  std::vector<double> med(methods);
  for (std::size_t m = 0; m < methods; ++m) med[m] = median(ms[m]);
  // The FCL ratio is against the faster of its two ways with deforming objects.
  const std::size_t fc = med[fr] <= med[fb] ? fr : fb;
  std::size_t tris = 0;
  for (const Object& o : (seq ? objects : fixed)) tris += o.mesh.triangles.size();
  std::printf("peelcd bench: %s, %zu frames, %zu objects, %zu triangles, %s, %s (%s), medians per frame after an untimed pass\n",
              a.scene.c_str(), frames, (seq ? objects : fixed).size(), tris,
              base.resolution ? (std::to_string(base.resolution) + "^2 per ROI").c_str()
                              : ("a " + std::to_string(base.budget) + "^2 budget shared by the ROIs").c_str(),
              runner.backend().c_str(), runner.renderer().c_str());
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("threads: CGAL and FCL %u (object pairs spread over them); peelcd host resolve %u lanes, llvmpipe %s, "
              "culling and exact CPU path %u, broad phase and the image stage's narrow phase 1\n",
              threads, threads, lp ? (std::string("LP_NUM_THREADS=") + lp).c_str() : "its default (one per core)", threads);
  std::printf("router (default row): %zu of %zu ROIs to the exact CPU path over the timed frames\n", rois_routed_exact, rois);
  std::printf("%-36s %10s %8s %7s %8s %8s %8s\n", "method", "median ms", "miss", "false", "x CGAL", "x FCL", "x floor");
  for (std::size_t m = 0; m < methods; ++m) {
    const bool is_floor = m >= fl;
    std::printf("%-36s %10.2f", names[m].c_str(), med[m]);
    if (is_floor) std::printf(" %8s %7s", "-", "-");
    else std::printf(" %7.2f%% %7zu", 100.0 * scores[m].miss_ratio(), scores[m].false_contacts);
    if (m < cg) {
      const std::size_t floor = configs[m].opt.cull == Cull::box ? fl : cfl;
      std::printf(" %8.2f %8.2f %8.2f\n", med[m] / med[cg], med[m] / med[fc], med[floor] > 0 ? med[m] / med[floor] : 0.0);
    } else {
      std::printf("\n");
    }
  }
  std::printf("(miss / false: over all frames against the exact pairs; FCL's triangle test is not exact; the floor finds nothing.\n"
              " x CGAL: against the cropped CGAL peer; x FCL: against the faster FCL row (%s); x floor: against one bare\n"
              " draw of the triangles the configuration would draw, one view. FCL trees kept: %zu (refit row), %zu (rebuilt\n"
              " row); refits %zu; cropped per-pair trees %zu and %zu, all frames.)\n",
              fc == fr ? "refit" : "rebuilt", fcl_refit.builds(), fcl_rebuild.builds(), fcl_refit.refits(),
              fcl_refit.pair_builds(), fcl_rebuild.pair_builds());
  if (seq && phase_ms.size() > 1) {
    std::printf("\nper phase, median ms:\n%-7s", "phase");
    for (const Config& c : configs) std::printf(" %9s", c.column.c_str());
    for (const char* peer : {"CGAL", "FCL refit", "FCL build", "floor", "cfloor"}) std::printf(" %9s", peer);
    std::printf(" %9s %9s\n", "dflt/CGAL", "dflt/FCL");
    for (std::size_t p = 0; p < phase_ms.size(); ++p) {
      std::printf("(%c)    ", char('a' + p));
      if (phase_ms[p][0].empty()) {  // fewer frames than phases
        std::printf(" no frames\n");
        continue;
      }
      std::vector<double> pm(methods);
      for (std::size_t m = 0; m < methods; ++m) std::printf(" %9.2f", pm[m] = median(phase_ms[p][m]));
      std::printf(" %9.2f %9.2f\n", pm[0] / pm[cg], pm[0] / std::min(pm[fr], pm[fb]));
    }
  }
  if (!a.csv.empty()) write_output(a.csv, csv);
  return 0;
}

struct SweepArgs {
  std::string scene;
  std::vector<int> res = {128, 256};
  std::vector<std::string> ids = {"unique", "paper"};
  std::vector<std::string> modes = {"paper", "full", "conservative"};  // conservative: the default
  std::vector<double> slopes = {1.0};
  std::vector<int> views = {1};
  std::vector<std::string> culls = {"contact"};
  double theta_step = 30, phi_step = 10;
  std::string csv, plot;
  std::string backend = kDefaultBackend;
  std::string shard;  // "K/N": the K-th of N deterministic slices of the view directions
};

// "K/N" (1 <= K <= N): which slice of a sharded run this is, as {K - 1, N}; {0, 1} when empty.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& text, const std::string& what) {
  if (text.empty()) return {0, 1};
  std::size_t k = 0, n = 0;
  char slash = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%zu%c%zu%c", &k, &slash, &n, &rest) != 3 || slash != '/' || k < 1 || n < 1 || k > n)
    throw InputError(what + " --shard \"" + text + "\": expected K/N with 1 <= K <= N, e.g. 2/8");
  return {k - 1, n};
}

// Runs the plot script on a sweep CSV (Debian's interpreter, where python3-matplotlib lives,
// unless PYTHON names another).
void plot_sweep(const std::string& csv_path, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const char* python = std::getenv("PYTHON");
  const std::string py = python ? python : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  const std::string cmd = "'" + py + "' '" + cli::data_dir("scripts") + "/plot_sweep.py' '" + csv_path + "' '" + dir + "'";
  if (std::system(cmd.c_str()) != 0)
    throw InputError("peelcd sweep: plotting failed (needs python3-matplotlib): " + cmd);
}

// peelcd sweep merge: the CSVs of sharded sweeps joined into one, rows in (configuration, theta,
// phi) order, each (configuration, direction) once.
struct SweepMergeArgs {
  std::vector<std::string> inputs;
  std::string csv, plot;
};

int run_sweep_merge(const SweepMergeArgs& a) {
  if (!a.csv.empty()) check_output_path(a.csv, "peelcd sweep merge: --csv");
  if (!a.plot.empty()) check_output_dir(a.plot, "peelcd sweep merge: --plot");
  refuse_overwriting_input(a.csv, a.inputs, "peelcd sweep merge: --csv");
  struct Row {
    std::size_t config;
    double theta, phi;
    std::string line, file;
  };
  std::string header;
  std::vector<std::string> labels;
  std::vector<Row> rows;
  for (const std::string& path : a.inputs) {
    std::ifstream in(path);
    if (!in) throw InputError("peelcd sweep merge: '" + path + "': cannot read it");
    std::string first, line;
    if (!std::getline(in, first) || first.rfind("config,", 0) != 0)
      throw InputError("peelcd sweep merge: '" + path + "': not a sweep CSV (no \"config,...\" header)");
    if (header.empty()) header = first;
    else if (first != header)
      throw InputError("peelcd sweep merge: '" + path + "': its columns differ from '" + a.inputs[0] + "'");
    std::size_t number = 1;
    while (std::getline(in, line)) {
      ++number;
      if (line.empty()) continue;
      // "label",resolution,ids,mode,slope,views,theta,phi,...
      const std::size_t close = line.find("\",", 1);
      std::vector<std::string> cols;
      if (close != std::string::npos) {
        std::istringstream fields(line.substr(close + 2));
        std::string f;
        while (std::getline(fields, f, ',')) cols.push_back(f);
      }
      const std::string where = "peelcd sweep merge: '" + path + "' line " + std::to_string(number);
      if (line.front() != '"' || cols.size() < 7) throw InputError(where + ": malformed row");
      double theta = 0, phi = 0;
      try {
        theta = std::stod(cols[5]);
        phi = std::stod(cols[6]);
      } catch (const std::exception&) {
        throw InputError(where + ": malformed theta or phi");
      }
      const std::string label = line.substr(1, close - 1);
      const auto it = std::find(labels.begin(), labels.end(), label);
      const std::size_t config = std::size_t(it - labels.begin());
      if (it == labels.end()) labels.push_back(label);
      rows.push_back({config, theta, phi, line, path});
    }
  }
  std::stable_sort(rows.begin(), rows.end(), [](const Row& x, const Row& y) {
    return std::tie(x.config, x.theta, x.phi) < std::tie(y.config, y.theta, y.phi);
  });
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].config == rows[i - 1].config && rows[i].theta == rows[i - 1].theta && rows[i].phi == rows[i - 1].phi)
      throw InputError("peelcd sweep merge: \"" + labels[rows[i].config] + "\" at theta " + std::to_string(rows[i].theta) +
                       ", phi " + std::to_string(rows[i].phi) + " is in both '" + rows[i - 1].file + "' and '" +
                       rows[i].file + "' (the shards overlap)");
  std::string out = header;
  for (const Row& r : rows) out += "\n" + r.line;
  std::fprintf(a.csv == "-" ? stderr : stdout, "sweep merge: %zu rows from %zu files, %zu configurations\n",
               rows.size(), a.inputs.size(), labels.size());
  std::string csv_path = a.csv;
  if (csv_path.empty() && !a.plot.empty()) {
    std::filesystem::create_directories(a.plot);
    csv_path = a.plot + "/sweep.csv";
  }
  if (!csv_path.empty()) write_output(csv_path, out);
  if (!a.plot.empty()) plot_sweep(csv_path, a.plot);
  return 0;
}

int run_sweep_command(const SweepArgs& a) {
  if (!a.csv.empty()) check_output_path(a.csv, "peelcd sweep: --csv");
  if (!a.plot.empty()) check_output_dir(a.plot, "peelcd sweep: --plot");
  const Scene scene = load_scene(a.scene);
  refuse_overwriting_input(a.csv, scene_inputs(scene), "peelcd sweep: --csv");
  const std::vector<Object> objects = load_objects(scene);
  std::vector<SweepConfig> configs;
  for (int res : a.res)
    for (const std::string& ids_name : a.ids) {
      const auto ids = parse_id_mode(ids_name);
      if (!ids) throw InputError("peelcd sweep: --ids: unknown ID mode \"" + ids_name + "\" (expected paper, ring or unique)");
      for (const std::string& mode : a.modes) {
        if (mode != "paper" && mode != "alternate" && mode != "full" && mode != "conservative")
          throw InputError("peelcd sweep: --mode: unknown mode \"" + mode +
                           "\" (expected paper, alternate, full or conservative)");
        for (int views : a.views)
          for (double slope : mode == "paper" || mode == "conservative" ? std::vector<double>{0.0} : a.slopes)
            for (const std::string& cull_name : a.culls) {
              SweepConfig c;
              c.cull = parsed(cull_name, parse_cull, "peelcd sweep: --cull: unknown culling", "contact or box");
              c.resolution = res;
              c.ids = *ids;
              c.peel = mode == "full" ? PeelMode::full : PeelMode::alternate;
              c.conservative = mode == "conservative";
              c.slope = slope;
              c.views = views;
              configs.push_back(c);
            }
      }
    }
  const auto [shard, shards] = parse_shard(a.shard, "peelcd sweep:");
  const auto all_directions = sweep_directions(a.theta_step, a.phi_step);
  std::vector<std::pair<double, double>> directions;
  for (std::size_t i = 0; i < all_directions.size(); ++i)
    if (i % shards == shard) directions.push_back(all_directions[i]);
  if (shards > 1)
    std::fprintf(stderr, "sweep: shard %zu/%zu: %zu of %zu view directions\n", shard + 1, shards, directions.size(),
                 all_directions.size());
  Runner runner = make_runner(a.backend);
  for (int res : a.res)
    if (res > runner.stage->max_resolution())
      throw InputError("peelcd sweep: --res " + std::to_string(res) + " is above GL_MAX_TEXTURE_SIZE " +
                       std::to_string(runner.stage->max_resolution()));
  const auto rows = run_sweep(*runner.detector, objects, configs, directions, Progress("views"));

  std::printf("sweep: %s, %zu views per configuration (theta step %g, phi step %g), %s\n", a.scene.c_str(),
              directions.size(), a.theta_step, a.phi_step, runner.renderer().c_str());
  std::printf("%-46s %9s %9s %9s %6s %11s %6s %11s %11s\n", "configuration", "avg miss", "max miss", "min miss",
              "false", "candidates", "eff", "median ms", "mean ms");
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const SweepSummary s = summarize(rows, c);
    std::printf("%-46s %8.2f%% %8.2f%% %8.2f%% %6zu %11.0f %5.1f%% %11.2f %11.2f\n", configs[c].label().c_str(),
                100 * s.avg_miss, 100 * s.max_miss, 100 * s.min_miss, s.false_contacts, s.mean_candidates,
                100 * s.mean_efficiency, s.median_total_ms, s.mean_total_ms);
  }
  std::string csv_path = a.csv;
  if (csv_path.empty() && !a.plot.empty()) {
    std::filesystem::create_directories(a.plot);
    csv_path = a.plot + "/sweep.csv";
  }
  if (!csv_path.empty()) write_output(csv_path, sweep_csv(rows, configs));
  if (!a.plot.empty()) plot_sweep(csv_path, a.plot);
  return 0;
}

// Number checks with messages a person can read. CLI11's own let "nan" through (every
// comparison with NaN is false; a NaN here would read as "not given") and print the range up
// to DBL_MAX in full.
CLI::Validator finite_number(bool (*ok)(double), const char* need, const char* name) {
  return CLI::Validator(
      [ok, need](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::out_of_range&) {
          return "Value " + text + " is not a finite number";
        } catch (const std::exception&) {
          return "Value " + text + " is not a number";
        }
        if (used != text.size()) return "Value " + text + " is not a number";
        if (!std::isfinite(v)) return "Value " + text + " is not a finite number";
        return ok(v) ? std::string() : "Value " + text + " " + need;
      },
      name);
}
const CLI::Validator kFinite = finite_number([](double) { return true; }, "", "FINITE");
const CLI::Validator kPositive = finite_number([](double v) { return v > 0.0; }, "is not positive", "POSITIVE");
const CLI::Validator kNonNegative = finite_number([](double v) { return v >= 0.0; }, "is negative", "NONNEGATIVE");

// The options that shape a frame, shared by detect and dump (they override the scene file's).
// The frame's options, one flag per row of the option table (peelcd/core/options.h), and the
// GL stage's and the command line's own.
void add_frame_options(CLI::App* c, DetectArgs& d) {
  for (const OptionSpec& spec : option_table()) {
    if (!spec.flag) continue;
    if (spec.kind == OptionSpec::Kind::boolean) {
      c->add_flag(spec.flag, d.flags_on[spec.key], spec.help);
      c->add_flag(std::string("--no-") + (spec.flag + 2), d.flags_off[spec.key],
                  std::string("Turns ") + spec.flag + " off");
      continue;
    }
    std::string type = spec.kind == OptionSpec::Kind::choice ? "{" + std::string(spec.choices) + "}"
                       : spec.kind == OptionSpec::Kind::integer ? "INT" : "NUMBER";
    const auto g = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.10g", x);
      return std::string(buf);
    };
    if (spec.kind != OptionSpec::Kind::choice && std::isfinite(spec.min))
      type += std::isfinite(spec.max) ? " in [" + g(spec.min) + ", " + g(spec.max) + "]" : " >= " + g(spec.min);
    // Stored as text, checked after parsing by the table (merged_options): one set of rules.
    c->add_option_function<std::string>(
         spec.flag, [&d, key = std::string(spec.key)](const std::string& v) { d.options[key] = v; }, spec.help)
        ->type_name(type);
  }
  c->add_option("--peeler", d.peeler, "How layers are made: abuffer (one draw into a per-texel k-buffer of fragments; default) "
                                      "or multipass (one draw per layer); the same layers either way");
  c->add_option("--resolve", d.resolve, "Where the k-buffer becomes layers and PCS: auto (host on a software renderer such as "
                                        "llvmpipe, else gpu; default), gpu (a compute pass) or host (mapped, resolved on the CPU)");
  c->add_flag("--no-batch", d.no_batch, "GL stage: draw each conservative ROI view on its own instead of packing the "
                                        "frame's views into one k-buffer and one draw (the same results; for comparison)");
  c->add_flag("--paper", d.paper,
              "The paper's configuration: point sampling, alternate peeling, paper IDs, constant epsilon, one view "
              "along world x, no culling (other options given override it)");
  c->add_option("--backend", d.backend, "Image stage: osmesa (software GL, the reference), egl (GPU, or Mesa without one) or cpu (no GL)")
      ->capture_default_str();
}

struct ClassesArgs {
  std::string backend = kDefaultBackend;
  int repeat = 5;
  int grid = 20;
  std::string only;
};

// The configurations docs/accuracy.md compares on every class: the image stage's (Stage::image:
// the router would send most of these small ROIs to the exact CPU path, which measures nothing
// about the image stage), then detect's default with its router.
std::vector<std::pair<std::string, DetectOptions>> class_configs() {
  std::vector<std::pair<std::string, DetectOptions>> out;
  out.emplace_back("paper", paper_options());
  DetectOptions old;  // the point-sampling default before conservative mode (0.2.0)
  old.stage = Stage::image;
  old.conservative = false;
  old.ids = IdMode::ring;
  old.theta = old.phi = old.roll = 0.0;
  old.views = 3;
  out.emplace_back("point, axis frame, 3 views", old);
  DetectOptions point;
  point.stage = Stage::image;
  point.conservative = false;
  point.ids = IdMode::ring;
  point.views = 3;
  out.emplace_back("point, generic frame, 3 views", point);
  DetectOptions conservative;
  conservative.stage = Stage::image;
  out.emplace_back("conservative (image stage)", conservative);
  DetectOptions tight = conservative;
  tight.resolution = 16;
  out.emplace_back("conservative, 16^2 tiles", tight);
  out.emplace_back("default (stage auto)", DetectOptions{});
  return out;
}

int run_classes(const ClassesArgs& a) {
  Runner runner = make_runner(a.backend, gl::GlOptions{});
  std::printf("peelcd classes: %s (%s); median of %d frames; grid %dx%d\n", runner.backend().c_str(),
              runner.renderer().c_str(), a.repeat, a.grid, a.grid);
  std::printf("%-24s %-32s %7s %7s %7s %9s %9s %11s %9s\n", "class", "configuration", "exact", "found", "missed",
              "miss %", "len miss%", "candidates", "ms");
  for (const GeometryClass& g : geometry_classes(a.grid)) {
    if (!a.only.empty() && g.name != a.only) continue;
    for (const auto& [name, opt] : class_configs()) {
      const ClassRow r = measure_class(*runner.detector, g, name, opt, a.repeat);
      std::printf("%-24s %-32s %7zu %7zu %7zu %9.3f %9.3f %11zu %9.2f\n", g.name.c_str(), name.c_str(), r.exact, r.found,
                  r.missed, 100.0 * r.miss_ratio(), 100.0 * r.missed_length_share(), r.candidates, r.median_ms);
      std::fflush(stdout);
    }
  }
  return 0;
}

struct CalibrateArgs {
  std::string backend = kDefaultBackend;
  int repeat = 5;
  std::vector<int> budgets = {128, 512};
};

int run_calibrate(const CalibrateArgs& a) {
  Runner runner = make_runner(a.backend, gl::GlOptions{});
  std::printf("peelcd calibrate: %s (%s); median of %d frames per stage\n", runner.backend().c_str(),
              runner.renderer().c_str(), a.repeat);
  const Calibration cal = calibrate(*runner.detector, cli::data_dir("fixtures/meshes"), a.budgets, a.repeat);
  std::printf("%-28s %9s %6s %10s %10s %9s %9s %7s\n", "scene", "triangles", "tile", "image ms", "exact ms",
              "image cand", "exact cand", "faster");
  for (const CalibrationRow& r : cal.rows)
    std::printf("%-28s %9zu %6d %10.3f %10.3f %9zu %9zu %7s\n", r.scene.c_str(), r.triangles, r.tile, r.image_ms, r.exact_ms,
                r.image_candidates, r.exact_candidates, r.image_ms < r.exact_ms ? "image" : "exact");
  const StageCost in_image = runner.stage->cost(), in_exact = exact_path_cost();
  std::printf("\nfitted  image: view_ms %.4f  triangle_us %.4f  texel_ns %.4f\n", cal.image.view_ms, cal.image.triangle_us,
              cal.image.texel_ns);
  std::printf("fitted  exact: view_ms %.4f  triangle_us %.4f\n", cal.exact.view_ms, cal.exact.triangle_us);
  std::printf("in use  image: view_ms %.4f  triangle_us %.4f  texel_ns %.4f\n", in_image.view_ms, in_image.triangle_us,
              in_image.texel_ns);
  std::printf("in use  exact: view_ms %.4f  triangle_us %.4f\n", in_exact.view_ms, in_exact.triangle_us);
  std::printf("router with the fitted models: %zu of %zu ROIs on the slower stage, %.3f ms lost of %.3f ms best\n",
              cal.wrong_fitted, cal.rows.size(), cal.lost_ms_fitted, cal.best_ms);
  std::printf("router with the models in use: %zu of %zu ROIs on the slower stage, %.3f ms lost of %.3f ms best\n",
              cal.wrong_in_use, cal.rows.size(), cal.lost_ms_in_use, cal.best_ms);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peelcd: image-space collision detection between triangle meshes through "
               "alternate surface peeling (OSMesa reference backend)"};
  app.set_version_flag("--version", std::string("peelcd ") + PEELCD_VERSION_STRING);
  app.formatter(std::make_shared<HelpFormatter>());  // subcommands inherit it
  app.require_subcommand(1);
  DetectArgs d;
  CLI::App* detect = app.add_subcommand(
      "detect", "Run one frame of collision detection on a scene file or on mesh files and report the colliding "
                "triangle pairs (indices in each mesh file's triangle order)");
  detect->add_option("input", d.inputs, "A scene JSON file, or two or more mesh files (OBJ, PLY, STL, glTF, ...: "
                                        "identity transforms, named by their file names, default options)")
      ->required();
  add_frame_options(detect, d);
  detect->add_option("--json", d.json_out, "Write the JSON report to FILE, or - for stdout")->check(kOutputPath);
  detect->add_flag("--list", d.list, "Print every colliding triangle pair (A's triangle, B's) after the summary");
  detect->add_flag("--status", d.status,
                   "Exit status for scripts, as grep's: 0 when anything collides, 1 when nothing does (2 bad input, 3 --max-miss)");
  detect->add_option("--repeat", d.repeat, "Run the frame N times and report median timings")
      ->check(kPositive);
  CLI::Option* check_flag =
      detect->add_flag("--check", d.check, "Also run the exact all-pairs reference and print the miss ratio");
  detect->add_option("--max-miss", d.max_miss,
                     "With --check: exit 3 when the frame's miss ratio (missed / exact pairs, all object pairs) is "
                     "above PCT percent (default: report only)")
      ->check(CLI::Range(0.0, 100.0))
      ->needs(check_flag);
  detect->add_flag("--quiet", d.quiet, "No human summary");
  detect->add_option("--explain-misses", d.explain_misses,
                     "With --check: run `peelcd explain` on the first N missed pairs and print their verdicts")
      ->check(kPositive)
      ->needs(check_flag);

  DetectArgs ex;
  ExplainArgs explain_args;
  CLI::App* explain = app.add_subcommand(
      "explain", "Say why one triangle pair was found or missed: the exact answer, the ROI, culling, and per view "
                 "the fragments, the layers and the PCS tests at the segment's texels, then a one-line verdict "
                 "(docs/debugging.md)");
  explain->add_option("input", ex.inputs, "A scene JSON file, or two or more mesh files (as detect)")->required();
  explain->add_option("--pair", explain_args.pair, "The pair: OBJ_A:TRI_A,OBJ_B:TRI_B (object name or index, triangle index)")
      ->required();
  add_frame_options(explain, ex);
  explain->add_option("--out", explain_args.out, "Write a page (index.html, one zoomed picture per view, "
                                                 "explain.json) to this folder (must not exist, or be empty)")->check(kOutputPath);
  explain->add_option("--json", ex.json_out, "Write the explanation as JSON to FILE, or - for stdout")->check(kOutputPath);
  explain->add_flag("--quiet", ex.quiet, "No text report");

  DetectArgs du;
  CLI::App* dump = app.add_subcommand(
      "dump", "Run one frame and write every peel layer of every ROI view (EXR, lossless; PNG previews), "
              "the PCS, the colliding pairs, meta.json and a self-contained index.html viewer to a folder");
  dump->add_option("input", du.inputs, "A scene JSON file, a glTF scene, or two or more mesh files (as detect)")->required();
  DumpArgs dump_args;
  dump->add_option("--out", dump_args.out, "Output folder (must not exist, or be empty)")->check(kOutputPath)->required();
  dump->add_option("--pair", dump_args.pair, "Only the ROI of objects A and B (names from the scene), e.g. --pair ball3,ball7");
  dump->add_option("--max-rois", dump_args.max_rois, "Refuse a frame with more ROIs than this (a dump writes a folder "
                                                     "per ROI and view); name one with --pair")
      ->check(kPositive)->capture_default_str();
  add_frame_options(dump, du);
  dump->add_flag("--quiet", du.quiet, "No summary line");

  GoldenArgs gr, gc;
  CLI::App* golden = app.add_subcommand("golden", "Record goldens from OSMesa, or compare a backend with them");
  golden->require_subcommand(1);
  CLI::App* record = golden->add_subcommand(
      "record", "Write the goldens of CASE... (default: every case) from the OSMesa reference backend into "
                "<golden-dir>/<case>/expected; review the change like code");
  record->add_option("case", gr.cases, "Case names (folders of the golden dir)");
  record->add_option("--golden-dir", gr.dir,
                     "Folder of the golden cases (default: fixtures/golden of the source tree, or share/peelcd "
                     "when installed, or $PEELCD_DATA_DIR)");
  CLI::App* compare = golden->add_subcommand(
      "compare", "Run CASE... (default: every case) on a backend and compare every layer, the PCS and the "
                 "colliding pairs with the goldens; on a difference print the first differing texels and "
                 "write a report with expected / actual / error-mask PNGs. Exit 1 if any case differs");
  compare->add_option("case", gc.cases, "Case names (folders of the golden dir)");
  compare->add_option("--golden-dir", gc.dir,
                      "Folder of the golden cases (default: fixtures/golden of the source tree, or share/peelcd "
                      "when installed, or $PEELCD_DATA_DIR)");
  compare->add_option("--backend", gc.backend, "GL backend: osmesa or egl")->capture_default_str();
  compare->add_option("--tier", gc.tier, "auto (exact on llvmpipe, hardware otherwise), exact or hardware")
      ->capture_default_str();
  compare->add_option("--report", gc.report, "Folder for the reports of differing cases")->check(kOutputPath)->capture_default_str();
  compare->add_option("--peeler", gc.peeler, "abuffer or multipass (default: the default, abuffer)");
  compare->add_option("--resolve", gc.resolve, "auto, gpu or host: where the k-buffer is resolved (default: auto)");
  compare->add_option("--repeat", gc.repeat, "Run and compare each case N times in one process (determinism)")
      ->check(kPositive)->capture_default_str();
  compare->add_option("--shard", gc.shard, "Compare the K-th of N deterministic slices of the cases (K/N)");
  compare->add_option("--require-renderer", gc.require_renderer,
                      "Skip (exit 77, for ctest) unless GL_RENDERER contains TEXT, e.g. zink");
  CompareDumpsArgs cd;
  CLI::App* compare_dumps = golden->add_subcommand(
      "compare-dumps", "Compare two dump folders from any producers (docs/dump-format.md) under a tier: exit 0 when "
                       "they agree, 1 when they differ (first differing texels printed; report with expected / "
                       "actual / error-mask PNGs), 2 when a dump is malformed");
  compare_dumps->add_option("expected", cd.expected, "The reference dump folder (e.g. a golden's expected/)")->required();
  compare_dumps->add_option("actual", cd.actual, "The dump folder to check")->required();
  compare_dumps->add_option("--tier", cd.tier, "exact (every word) or hardware (another rasterizer's tolerances)")
      ->capture_default_str();
  compare_dumps->add_option("--report", cd.report, "Folder for the report when they differ")->check(kOutputPath)->capture_default_str();
  SimArgs si;
  CLI::App* simulate = app.add_subcommand(
      "simulate", "Run the paper's dynamic scenes (test1: a walking raptor among 40 billiard balls; test2: a "
                  "tearing cloth with 40 falling objects) and print per-frame nCTP, counters and stage times, "
                  "and a summary per phase beside the paper's Tables 1 and 2");
  simulate->add_option("test", si.test, "test1, test2 or crowd (a pile of --objects balls in light contact)")
      ->required()->check(CLI::IsMember({"test1", "test2", "crowd"}));
  simulate->add_option("--objects", si.objects, "Balls of the crowd scene")->check(CLI::Range(2, 5000))
      ->capture_default_str();
  simulate->add_option("--frames", si.frames, "Frames")->check(kPositive)->capture_default_str();
  add_frame_options(simulate, si.detect);
  simulate->add_flag("--no-rigid", si.no_rigid, "Pass the rigid objects as plain triangles (no shape caching)");
  simulate->add_option("--csv", si.csv, "Write one row per frame to FILE, or - for stdout")->check(kOutputPath);

  BenchArgs be;
  CLI::App* benchmark = app.add_subcommand(
      "bench", "Time peelcd's configurations, CGAL (cropped to the overlap box), FCL 0.7 (rigid trees kept, "
               "deforming ones refitted or rebuilt, its own broad phase) and the bare-draw floor side by side on "
               "the same frames; print medians, miss ratios and ratios");
  benchmark->add_option("scene", be.scene, "test1, test2, crowd or a scene file")->capture_default_str();
  benchmark->add_option("--objects", be.objects, "Balls of the crowd scene")->check(CLI::Range(2, 5000))
      ->capture_default_str();
  benchmark->add_option("--threads", be.threads, "Threads of the peers, of peelcd's host resolve and of llvmpipe "
                                                 "(LP_NUM_THREADS); 0 = one per core, at most 8")
      ->check(CLI::Range(0, 64))->capture_default_str();
  benchmark->add_option("--frames", be.frames, "Frames (of the test scene; repeats of a scene file)")
      ->check(kPositive)->capture_default_str();
  benchmark->add_option("--res", be.res, "Texture size per ROI for peelcd; 0 = share the 512^2 budget with "
                                         "tiles by need, as detect does")->capture_default_str()
      ->check(kNonNegative);
  benchmark->add_option("--backend", be.backend, "GL backend: osmesa or egl")->capture_default_str();
  benchmark->add_option("--csv", be.csv, "Write one row per (frame, method) to FILE, or - for stdout")->check(kOutputPath);

  SweepArgs sw;
  CLI::App* sweep = app.add_subcommand(
      "sweep", "Measure accuracy and run time over view directions and configurations against the "
               "exact reference; prints a summary per configuration (average/max/min miss ratio)");
  sweep->add_option("scene", sw.scene, "Scene JSON file");
  sweep->add_option("--shard", sw.shard, "Run the K-th of N deterministic slices of the view directions (K/N, "
                                         "e.g. 3/8); join the shards' CSVs with: peelcd sweep merge");
  SweepMergeArgs sm;
  CLI::App* sweep_merge = sweep->add_subcommand(
      "merge", "Join the CSVs of sharded sweeps (sweep --shard K/N --csv ...) into one, in (configuration, view) "
               "order, each row once");
  sweep_merge->add_option("csv_files", sm.inputs, "The shards' CSV files")->required();
  sweep_merge->add_option("--csv", sm.csv, "Write the joined CSV to FILE, or - for stdout")->check(kOutputPath);
  sweep_merge->add_option("--plot", sm.plot, "Write heat maps and the run-time-against-miss-ratio plot to DIR (matplotlib)")->check(kOutputPath);
  sweep->add_option("--res", sw.res, "Resolutions (comma-separated)")->delimiter(',')->check(kPositive)
      ->capture_default_str();
  sweep->add_option("--ids", sw.ids, "ID modes: unique, paper, ring (comma-separated)")->delimiter(',')
      ->capture_default_str();
  sweep->add_option("--mode", sw.modes,
                    "Modes: paper (alternate peeling, constant epsilon: the paper), alternate (alternate "
                    "peeling, slope epsilon), full (full peeling, slope epsilon), conservative (intervals)")
      ->delimiter(',')->capture_default_str();
  sweep->add_option("--slope", sw.slopes, "Slope-epsilon factors for the non-paper modes")->delimiter(',')
      ->check(kNonNegative)->capture_default_str();
  sweep->add_option("--views", sw.views, "Fused views per ROI: 1, 2 and/or 3")->delimiter(',')
      ->check(CLI::IsMember({1, 2, 3}))->capture_default_str();
  sweep->add_option("--cull", sw.culls, "Culling: contact and/or box (see detect --cull)")->delimiter(',')
      ->capture_default_str();
  sweep->add_option("--theta-step", sw.theta_step, "Longitude step, degrees")->check(kFinite)
      ->check(CLI::Range(1.0, 360.0))->capture_default_str();
  sweep->add_option("--phi-step", sw.phi_step, "Latitude step, degrees")->check(kFinite)->check(CLI::Range(1.0, 90.0))
      ->capture_default_str();
  sweep->add_option("--backend", sw.backend, "GL backend: osmesa or egl")->capture_default_str();
  sweep->add_option("--csv", sw.csv, "Write one row per (configuration, view) to FILE, or - for stdout")->check(kOutputPath);
  sweep->add_option("--plot", sw.plot, "Write heat maps and the run-time-against-miss-ratio plot to DIR (matplotlib)")->check(kOutputPath);

  ClassesArgs ca;
  CLI::App* classes = app.add_subcommand(
      "classes", "Measure every configuration of docs/accuracy.md on the built-in classes of geometry (crossing "
                 "and touching boxes, a floor, coincident copies, zero-area triangles, a needle, open and "
                 "self-intersecting meshes, a crowded grid) against the exact reference");
  classes->add_option("--backend", ca.backend, "Image stage: osmesa, egl or cpu")->capture_default_str();
  classes->add_option("--repeat", ca.repeat, "Frames per measurement (median time)")->check(kPositive)
      ->capture_default_str();
  classes->add_option("--grid", ca.grid, "Side of the crowded grid (N x N spheres)")->check(CLI::Range(2, 64))
      ->capture_default_str();
  classes->add_option("--class", ca.only, "Only the class of this name");

  CalibrateArgs cal;
  CLI::App* calibrate_cmd = app.add_subcommand(
      "calibrate", "Time one-ROI scenes through the image stage and the exact CPU path and fit the stage router's "
                   "cost models (docs/performance.md, \"The stage router\")");
  calibrate_cmd->add_option("--backend", cal.backend, "Image stage: osmesa, egl or cpu")->capture_default_str();
  calibrate_cmd->add_option("--repeat", cal.repeat, "Frames per measurement (median)")->check(kPositive)
      ->capture_default_str();
  calibrate_cmd->add_option("--budgets", cal.budgets, "Texture budgets to time each scene at")
      ->check(CLI::Range(16, 16384))->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  try {
    if (*detect) return run_detect(d);
    if (*explain) return run_explain(ex, explain_args);
    if (*dump) return run_dump(du, dump_args);
    if (*simulate) return run_simulate(si);
    if (*benchmark) return run_bench(be);
    if (*record) {
      if (gr.dir.empty()) gr.dir = cli::data_dir("fixtures/golden");
      return run_golden_record(gr);
    }
    if (*compare) {
      if (gc.dir.empty()) gc.dir = cli::data_dir("fixtures/golden");
      return run_golden_compare(gc);
    }
    if (*compare_dumps) return run_compare_dumps(cd);
    if (*sweep_merge) return run_sweep_merge(sm);
    if (*sweep) {
      if (sw.scene.empty()) throw InputError("peelcd sweep: a scene file is required (or: peelcd sweep merge CSV...)");
      return run_sweep_command(sw);
    }
    if (*classes) return run_classes(ca);
    if (*calibrate_cmd) return run_calibrate(cal);
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const gl::GlError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: internal: %s\n", e.what());
    return 1;
  }
  return 0;
}
