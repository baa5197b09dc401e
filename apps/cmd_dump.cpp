// peelcd dump and golden (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/oracle/golden.h"
#include "peelcd/oracle/explain.h"

namespace peelcd::cli {

struct DumpArgs {
  std::string out;
  std::string pair;        // "A,B": only that pair's ROI
  std::size_t max_rois = 64;  // refuse larger dumps unless raised
};

// Each pair's reference pairs the frame did not report, explained on the same frame (one more run
// with every layer captured, only when something was missed): the viewer lists them with why.
void explain_missed(oracle::Dump& dump, const std::vector<Object>& objects, const DetectOptions& opt, Runner& runner,
                    const Progress& progress) {
  std::unique_ptr<oracle::FrameTrace> trace;
  for (oracle::DumpPair& p : dump.pairs) {
    // The IDs the viewer outlines for a searched pair: those of every colliding and missed pair.
    const auto id_of = [&](std::size_t object, std::uint32_t t) { return corner_id(objects[object].mesh, t, 2, opt.ids); };
    const auto note_ids = [&](std::uint32_t ta, std::uint32_t tb) {
      p.ids_a[ta] = id_of(p.object_a, ta);
      p.ids_b[tb] = id_of(p.object_b, tb);
    };
    for (const auto& c : p.colliding) note_ids(c[0], c[1]);
    if (!p.has_reference) continue;
    std::vector<std::array<std::uint32_t, 2>> missed = oracle::missed_pairs(p);
    for (const auto& m : missed) note_ids(m[0], m[1]);
    if (missed.size() > oracle::kMissedExplained) missed.resize(oracle::kMissedExplained);
    for (const auto& m : missed) {
      if (!trace) {
        progress.phase("peelcd dump: explaining the missed pairs...");
        trace = std::make_unique<oracle::FrameTrace>(*runner.detector, objects, opt);
      }
      const oracle::Explanation e = trace->explain(oracle::PairQuery{p.object_a, p.object_b, m[0], m[1]});
      std::string why = e.verdict_line;
      if (why.rfind("missed: ", 0) == 0) why.erase(0, 8);  // the file says it is missed
      p.missed.push_back({m[0], m[1], oracle::to_string(e.verdict), why});
    }
  }
}

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
  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.gl), a.costs);
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
  explain_missed(dump, objects, opt, runner, progress);
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
  std::map<std::string, std::string> gl;  // --peeler, --resolve (empty: the case's)
  std::string require_renderer;  // skip (exit 77) unless GL_RENDERER contains this
  bool one_view_only = false;    // skip the production path
  std::string shard;             // "K/N": every N-th case from the K-th
  int repeat = 1;
};

// ctest's SKIP_RETURN_CODE for a run that cannot take place here (the reason on stderr).
constexpr int kExitSkipped = 77;

// A report folder checked before any work: a folder (or nothing yet) that is not a dump and not
// inside one of `inputs` (the goldens, the dumps under test). Throws InputError naming it.
void check_report_dir(const std::string& report, const std::vector<std::string>& inputs, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (report.empty()) throw InputError(what + ": an empty folder name");
  if (fs::exists(report, ec) && !fs::is_directory(report, ec))
    throw InputError(what + " '" + report + "': exists and is not a folder");
  if (fs::exists(fs::path(report) / "meta.json", ec))
    throw InputError(what + " '" + report + "': it holds a dump (meta.json): a report goes elsewhere");
  const fs::path target = fs::weakly_canonical(report, ec);
  for (const std::string& in : inputs) {
    const fs::path dir = fs::weakly_canonical(in, ec);
    if (ec) continue;
    const auto [d, t] = std::mismatch(dir.begin(), dir.end(), target.begin(), target.end());
    if (d == dir.end())
      throw InputError(what + " '" + report + "': it is inside '" + in + "', which is under test: a report goes elsewhere");
  }
}

// A case's report folder made fresh: an earlier run's pictures there are removed first (the
// folder holds a report, never a dump: check_report_dir()).
void fresh_report(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(fs::path(dir) / "meta.json", ec)) throw InputError("peelcd: '" + dir + "' holds a dump, not a report");
  fs::remove_all(dir, ec);
}

std::vector<std::string> golden_cases(const GoldenArgs& a) {
  return a.cases.empty() ? oracle::golden_case_names(a.dir) : a.cases;
}

int run_golden_record(const GoldenArgs& a) {
  // Goldens come from the reference backend only.
  Runner runner = make_runner("osmesa");
  for (const std::string& name : golden_cases(a)) {
    const Scene scene = load_scene(oracle::golden_case_scene(a.dir, name));
    const std::vector<Object> objects = load_objects(scene);
    runner.use(scene.gl);
    const oracle::Dump dump = capture_frame(objects, scene.options, runner);
    oracle::record_golden_case(dump, a.dir, name);
    const std::string dir = oracle::golden_case_expected(a.dir, name);
    std::size_t layers = 0;
    for (const auto& p : dump.pairs)
      for (const auto& v : p.views) layers += v.layers.size();
    std::printf("recorded %s: %zu ROIs, %zu layers -> %s\n", name.c_str(), dump.pairs.size(), layers, dir.c_str());
  }
  return 0;
}

int run_golden_compare(const GoldenArgs& a) {
  check_report_dir(a.report, {a.dir}, "peelcd golden compare: --report");
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
  const std::vector<std::string> cases = oracle::golden_shard(all_cases, shard, shards);
  if (shards > 1) std::printf("golden compare: shard %zu/%zu: %zu of %zu cases\n", shard + 1, shards, cases.size(), all_cases.size());
  const Progress progress("cases", true);
  std::size_t done = 0;
  for (const std::string& name : cases) {
    progress(done++, cases.size());
    Scene scene = load_scene(oracle::golden_case_scene(a.dir, name));
    // A golden folder copied elsewhere: its cases reach their meshes through ../../meshes; one
    // not found there is read from peelcd's own fixtures/meshes, and said.
    for (SceneObject& o : scene.objects) {
      std::error_code ec;
      const std::filesystem::path rel = std::filesystem::path(o.mesh_path).lexically_normal().lexically_relative(
          (std::filesystem::path(oracle::golden_case_scene(a.dir, name)).parent_path() / "../../meshes").lexically_normal());
      if (std::filesystem::exists(o.mesh_path, ec) || rel.empty() || *rel.begin() == "..") continue;
      const std::string own = (std::filesystem::path(data_dir("fixtures/meshes")) / rel).string();
      if (!std::filesystem::exists(own, ec)) continue;
      std::printf("golden %s: mesh '%s' is not beside the goldens: read from '%s'\n", name.c_str(), o.mesh_path.c_str(),
                  own.c_str());
      o.mesh_path = own;
    }
    runner.use(merged_gl_options(scene, a.gl));
    const std::vector<Object> objects = load_objects(scene);
    const oracle::Dump expected = oracle::read_dump(oracle::golden_case_expected(a.dir, name));
    bool case_ok = true;
    for (int run = 0; run < std::max(1, a.repeat); ++run) {
      const oracle::Dump actual = capture_frame(objects, scene.options, runner);
      const oracle::Comparison c = oracle::compare_dumps(expected, actual, tier);
      const std::string label = (a.repeat > 1 ? name + " (run " + std::to_string(run + 1) + ")" : name) + ", one-view path";
      if (c.ok()) {
        std::printf("%s", oracle::report_text(c, label, tier).c_str());
        continue;
      }
      case_ok = false;
      fresh_report(a.report + "/" + name);
      std::printf("%s", oracle::write_report(expected, actual, c, label, a.report + "/" + name).c_str());
      break;
    }
    // The production path: what a GPU runs by default (views batched, GPU selection, the GPU
    // resolve unless --resolve host), no layer captured: its pairs against the golden's.
    if (!a.one_view_only && runner.gl) {  // the CPU stage has one path
      gl::GlOptions production = merged_gl_options(scene, a.gl);
      production.batch = true;
      production.gpu_select = true;
      const auto resolve = a.gl.find("resolve");
      if (resolve == a.gl.end() || resolve->second == "auto") production.resolve = Resolve::gpu;
      runner.use(production);
      DetectOptions opt = scene.options;
      opt.stage = Stage::image;
      const FrameResult frame = runner.detector->detect(objects, opt);
      const oracle::Comparison c = oracle::compare_production(expected, frame, opt.conservative);
      const std::string label = name + ", production path (batched, GPU selection, " +
                                std::string(production.resolve == Resolve::gpu ? "GPU" : "host") + " resolve)";
      std::printf("%s", oracle::report_text(c, label, tier).c_str());
      case_ok = case_ok && c.ok();
    }
    failed += case_ok ? 0 : 1;
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
  check_report_dir(a.report, {a.expected, a.actual}, "peelcd golden compare-dumps: --report");
  const oracle::Dump expected = oracle::read_dump(a.expected);
  const oracle::Dump actual = oracle::read_dump(a.actual);
  const oracle::Comparison c = oracle::compare_dumps(expected, actual, tier);
  const std::string label = a.expected + " vs " + a.actual;
  if (c.ok() && c.tolerated_texels == 0) {  // nothing to show
    std::printf("%s", oracle::report_text(c, label, tier).c_str());
    return 0;
  }
  // A failure, or texels within the tier's tolerance: the report and its page show them.
  fresh_report(a.report);
  std::printf("%s", oracle::write_report(expected, actual, c, label, a.report).c_str());
  return c.ok() ? 0 : 1;
}


std::vector<Command> add_dump_commands(CLI::App& app) {
  auto du_holder = std::make_shared<DetectArgs>();
  DetectArgs& du = *du_holder;
  CLI::App* dump = app.add_subcommand(
      "dump", "Run one frame and write every peel layer of every ROI view (EXR, lossless; PNG previews), "
              "the PCS, the colliding pairs, meta.json and a self-contained index.html viewer to a folder");
  dump->add_option("input", du.inputs, "A scene JSON file, a glTF scene, or two or more mesh files (as detect)")->required();
  auto dump_args_holder = std::make_shared<DumpArgs>();
  DumpArgs& dump_args = *dump_args_holder;
  dump->add_option("--out", dump_args.out, "Output folder (must not exist, or be empty)")->check(kOutputPath)->required();
  dump->add_option("--pair", dump_args.pair, "Only the ROI of objects A and B (names from the scene), e.g. --pair ball3,ball7");
  dump->add_option("--max-rois", dump_args.max_rois, "Refuse a frame with more ROIs than this (a dump writes a folder "
                                                     "per ROI and view); name one with --pair")
      ->check(kPositive)->capture_default_str();
  add_frame_options(dump, du);
  dump->add_flag("--quiet", du.quiet, "No summary line");

  return {{dump, [du_holder, dump_args_holder] { return run_dump(*du_holder, *dump_args_holder); }}};
}

std::vector<Command> add_golden_commands(CLI::App& app) {
  auto gr_holder = std::make_shared<GoldenArgs>();
  GoldenArgs& gr = *gr_holder;
  auto gc_holder = std::make_shared<GoldenArgs>();
  GoldenArgs& gc = *gc_holder;
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
  add_backend_option(compare, gc.backend);
  compare->add_option("--tier", gc.tier, "auto (exact on llvmpipe, hardware otherwise), exact or hardware")
      ->capture_default_str();
  compare->add_option("--report", gc.report, "Folder for the reports of differing cases")->check(kOutputPath)->capture_default_str();
  add_gl_options(compare, gc.gl, {"peeler", "resolve", "coverage"});
  compare->add_option("--repeat", gc.repeat, "Run and compare each case N times in one process (determinism)")
      ->check(kPositive)->capture_default_str();
  compare->add_option("--shard", gc.shard, "Compare the K-th of N deterministic slices of the cases (K/N)");
  compare->add_flag("--one-view-only", gc.one_view_only,
                    "Compare only the one-view path (every layer); by default each case also runs the production "
                    "path (views batched, GPU selection, GPU resolve) and compares its pairs");
  compare->add_option("--require-renderer", gc.require_renderer,
                      "Skip (exit 77, for ctest) unless GL_RENDERER contains TEXT, e.g. zink");
  auto cd_holder = std::make_shared<CompareDumpsArgs>();
  CompareDumpsArgs& cd = *cd_holder;
  CLI::App* compare_dumps = golden->add_subcommand(
      "compare-dumps", "Compare two dump folders from any producers (docs/dump-format.md) under a tier: exit 0 when "
                       "they agree, 1 when they differ (first differing texels printed; report with expected / "
                       "actual / error-mask PNGs), 2 when a dump is malformed");
  compare_dumps->add_option("expected", cd.expected, "The reference dump folder (e.g. a golden's expected/)")->required();
  compare_dumps->add_option("actual", cd.actual, "The dump folder to check")->required();
  compare_dumps->add_option("--tier", cd.tier, "exact (every word) or hardware (another rasterizer's tolerances)")
      ->capture_default_str();
  compare_dumps->add_option("--report", cd.report, "Folder for the report when they differ")->check(kOutputPath)->capture_default_str();
  return {{record,
           [gr_holder] {
             if (gr_holder->dir.empty()) gr_holder->dir = data_dir("fixtures/golden");
             return run_golden_record(*gr_holder);
           }},
          {compare,
           [gc_holder] {
             if (gc_holder->dir.empty()) gc_holder->dir = data_dir("fixtures/golden");
             return run_golden_compare(*gc_holder);
           }},
          {compare_dumps, [cd_holder] { return run_compare_dumps(*cd_holder); }}};
}
}  // namespace peelcd::cli
