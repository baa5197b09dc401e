// peelcd detect and explain (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/io/result_json.h"
#include "peelcd/oracle/explain.h"

#include <cstring>

namespace peelcd::cli {

// A pair's relation when the contacts do not say it all (containment, unknown), and its volume
// when asked for (with --check, against CGAL's exact volume).
void print_relation(FILE* human, const PairResult& p, const std::vector<Object>& objects, const DetectOptions& opt,
                    bool check) {
  const std::string& na = objects[p.object_a].name;
  const std::string& nb = objects[p.object_b].name;
  if (p.relation == Relation::a_inside_b || p.relation == Relation::b_inside_a)
    std::fprintf(human, "  inside: '%s' is inside '%s' (no surface contact; exact point-in-mesh test)%s%s\n",
                 (p.relation == Relation::a_inside_b ? na : nb).c_str(), (p.relation == Relation::a_inside_b ? nb : na).c_str(),
                 p.relation_note.empty() ? "" : ": ", p.relation_note.c_str());
  else if (p.relation == Relation::unknown)
    std::fprintf(human, "  relation unknown: %s\n", p.relation_note.c_str());
  if (opt.margin > 0.0) {
    if (p.near.within())
      std::fprintf(human, "  within %g: %zu triangle pairs; least distance %.9g between (%.6g, %.6g, %.6g) on '%s' and "
                   "(%.6g, %.6g, %.6g) on '%s'\n",
                   opt.margin, p.near.pairs.size(), p.near.distance, p.near.p.x(), p.near.p.y(), p.near.p.z(), na.c_str(),
                   p.near.q.x(), p.near.q.y(), p.near.q.z(), nb.c_str());
    else
      std::fprintf(human, "  within %g: no triangle pair\n", opt.margin);
  }
  if (opt.depth && p.object_a != p.object_b) {
    if (p.depth.known)
      std::fprintf(human, "  depth %.9g (+0/-%.1g) along (%.6f, %.6f, %.6f): moving '%s' that far separates it from '%s' "
                   "(least of %zu directions; the search began from the %s)\n",
                   p.depth.depth, 2.0 * p.depth.bound, p.depth.direction.x(), p.depth.direction.y(), p.depth.direction.z(),
                   na.c_str(), nb.c_str(), p.depth.directions, p.depth.source.c_str());
    else
      std::fprintf(human, "  depth unknown: %s\n", p.depth.reason.c_str());
  }
  if (!opt.volume || p.object_a == p.object_b) return;
  if (!p.volume.known) {
    std::fprintf(human, "  volume unknown: %s\n", p.volume.reason.c_str());
    return;
  }
  const Vec3& g = p.volume.gradient;
  std::fprintf(human, "  volume %.6g +- %.2g (%dx%d rays per axis); moving '%s' along (%.3g, %.3g, %.3g) reduces it\n",
               p.volume.volume, p.volume.error, p.volume.resolution, p.volume.resolution, na.c_str(), 0.0 - g.x(), 0.0 - g.y(),
               0.0 - g.z());
  if (!check) return;
  try {
    const double exact = exact_overlap_volume(objects[p.object_a].mesh, objects[p.object_b].mesh);
    const double err = std::abs(p.volume.volume - exact);
    std::fprintf(human, "  exact volume (CGAL corefinement): %.6g; error %.3g (%.3f%%), %s the estimate's +-%.2g\n", exact, err,
                 exact > 0 ? 100.0 * err / exact : 0.0, err <= p.volume.error ? "within" : "OUTSIDE", p.volume.error);
  } catch (const std::exception& e) {
    std::fprintf(human, "  exact volume: not computed (%s)\n", e.what());
  }
}

namespace {

// --check: every pair against the exact reference; the first missed pairs for --explain-misses.
struct CheckResult {
  Score total;
  std::vector<Score> scores;              // per pair
  std::vector<oracle::PairQuery> misses;  // in frame order
};

CheckResult check_pairs(const FrameResult& result, const std::vector<Object>& objects, const DetectOptions& opt,
                        std::size_t explain_misses) {
  CheckResult c;
  for (const PairResult& p : result.pairs) {
    const std::vector<std::uint64_t> exact = exact_pair_reference(objects, p.object_a, p.object_b, opt.self_adjacency);
    c.scores.push_back(score_contacts(exact, p.colliding));
    for (const std::uint64_t k : exact) {
      if (c.misses.size() >= explain_misses) break;
      const bool reported = std::any_of(p.colliding.begin(), p.colliding.end(), [&](const Contact& x) {
        return x.tri_a == pair_a(k) && x.tri_b == pair_b(k);
      });
      if (!reported) c.misses.push_back({p.object_a, p.object_b, pair_a(k), pair_b(k)});
    }
    c.total.exact += c.scores.back().exact;
    c.total.found += c.scores.back().found;
    c.total.missed += c.scores.back().missed;
    c.total.false_contacts += c.scores.back().false_contacts;
  }
  return c;
}

// The frame `repeat` times; with several, the per-stage medians reported.
FrameResult run_frames(Runner& runner, const std::vector<Object>& objects, const DetectOptions& opt, int repeat,
                       std::size_t& runs) {
  FrameResult result;
  std::vector<Timings> timings;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    result = runner.detector->detect(objects, opt);
    timings.push_back(result.timings);
  }
  runs = timings.size();
  if (timings.size() > 1) {
    const auto med = [&](double Timings::*f) {
      std::vector<double> v;
      for (const Timings& t : timings) v.push_back(t.*f);
      return median(v);
    };
    Timings m;
    for (double Timings::*f : {&Timings::aabb, &Timings::upload, &Timings::gpu, &Timings::readback, &Timings::cpu,
                               &Timings::total, &Timings::gl_wait, &Timings::gpu_raster, &Timings::gpu_compute,
                               &Timings::gpu_transfer, &Timings::gpu_select, &Timings::gpu_cover})
      m.*f = med(f);
    m.gpu_timed = result.timings.gpu_timed;
    m.gpu_passes_untimed = result.timings.gpu_passes_untimed;
    result.timings = m;
  }
  return result;
}

// The frame's header: configuration, the router's split, every fallback (never silent).
void print_frame_header(FILE* human, const Scene& scene, const std::vector<Object>& objects, const DetectOptions& opt,
                        const Runner& runner, const FrameResult& result) {
  std::fprintf(human, "peelcd detect: %s  (%zu objects, %s, %s)\n", scene.path.c_str(), objects.size(),
               runner.backend().c_str(), result.renderer.c_str());
  if (opt.conservative)
    std::fprintf(human, "conservative  view theta=%g phi=%g roll=%g  views=%d  ids=%s  cull=%s\n", opt.theta, opt.phi,
                 opt.roll, opt.views, to_string(opt.ids), to_string(opt.cull));
  else
    std::fprintf(human, "point sampling  view theta=%g phi=%g roll=%g  views=%d  ids=%s  peel=%s  slope=%g  cull=%s\n",
                 opt.theta, opt.phi, opt.roll, opt.views, to_string(opt.ids), to_string(opt.peel), opt.slope,
                 to_string(opt.cull));
  std::size_t culled_out = 0;  // pairs with no triangle of one object near the other: no path ran
  for (const PairResult& p : result.pairs) culled_out += std::strcmp(pair_path(p), "none") == 0 ? 1 : 0;
  std::fprintf(human, "stage %s: %zu of %zu ROIs by the exact CPU path, %zu peeled", to_string(opt.stage),
               result.rois_exact, result.pairs.size(), result.pairs.size() - result.rois_exact - culled_out);
  if (culled_out) std::fprintf(human, ", %zu with nothing to test (culled)", culled_out);
  if (opt.stage == Stage::automatic && !runner.stage->cost_models().source.empty())
    std::fprintf(human, " (router models from %s)", runner.stage->cost_models().source.c_str());
  if (result.views_exhaustive > 0)
    std::fprintf(human, " (%zu views fell back to the exhaustive exact test: k-buffer too deep or too large)",
                 result.views_exhaustive);
  if (result.gl_deep_texels > 0)
    std::fprintf(human, " (GPU resolve: %zu texels deeper than %d fragments split over invocations)",
                 result.gl_deep_texels, PEELCD_GPU_RESOLVE_DEPTH);
  if (result.gl_couples_apart > 0)
    std::fprintf(human, " (GPU resolve: %zu texel couples certainly apart, not read back)", result.gl_couples_apart);
  if (result.views_host_resolved > 0)
    std::fprintf(human, " (%zu views resolved on the host: a texel deeper than the GPU resolve's %d fragments)",
                 result.views_host_resolved, PEELCD_GPU_RESOLVE_DEPTH);
  std::fprintf(human, "\n");
  if (result.pairs.empty())
    std::fprintf(human, objects.size() == 1 && !opt.self && !objects[0].self
                            ? "one object, no pair: --self tests it against itself\n"
                            : "no overlapping bounding boxes: no GL work\n");
}

// One pair's line: the path it took and what it found.
void print_pair(FILE* human, const PairResult& p, const std::vector<Object>& objects, const DetectOptions& opt) {
  const char* na = objects[p.object_a].name.c_str();
  const char* nb = objects[p.object_b].name.c_str();
  if (std::strcmp(pair_path(p), "none") == 0) {
    std::fprintf(human, "%s x %s: no triangle of one near the other (culled: %zu+%zu tris in the ROI), nothing drawn "
                 "or tested\n", na, nb, p.triangles_in_roi_a, p.triangles_in_roi_b);
  } else if (p.exact_stage) {
    std::fprintf(human, "%s x %s: exact CPU path (predicted %.3f ms; image stage %.3f ms), %zu+%zu tris in the ROI, "
                 "%zu candidates, %zu colliding\n", na, nb, p.predicted_exact_ms, p.predicted_image_ms,
                 p.triangles_in_roi_a, p.triangles_in_roi_b, p.candidates, p.colliding.size());
  } else {
    char eps[48] = "";  // point sampling's threshold; the conservative stage has none
    if (!opt.conservative) std::snprintf(eps, sizeof eps, ", eps %.3g", p.epsilon);
    std::fprintf(human, "%s x %s: ROI %dx%d%s, drawn %zu+%zu of %zu+%zu tris, %d layers, %zu PCS, %zu candidates, %zu "
                 "colliding\n", na, nb, p.resolution, p.resolution, eps, p.triangles_drawn_a, p.triangles_drawn_b,
                 p.triangles_in_roi_a, p.triangles_in_roi_b, p.layers, p.pcs_count, p.candidates, p.colliding.size());
    if (p.views_exhaustive > 0)  // a fallback is never silent
      std::fprintf(human, "  path %s: %s\n", pair_path(p), pair_path_reason(p, opt).c_str());
  }
}

// Pairs of triangle indices (or IDs), ten to a line.
template <class List, class Get>
void print_index_pairs(FILE* human, const PairResult& p, const std::vector<Object>& objects, const char* what,
                       const List& list, const Get& get) {
  const char* na = objects[p.object_a].name.c_str();
  const char* nb = objects[p.object_b].name.c_str();
  std::fprintf(human, "%s x %s: %s (%s, %s)\n", na, nb, what, na, nb);
  std::string line = " ";
  for (const auto& c : list) {
    const auto [ta, tb] = get(c);
    line += " (" + std::to_string(ta) + "," + std::to_string(tb) + ")";
    if (line.size() > 90) {
      std::fprintf(human, "%s\n", line.c_str());
      line = " ";
    }
  }
  if (line.size() > 1) std::fprintf(human, "%s\n", line.c_str());
}

// The human summary: the header, each pair (with its check and relation), the totals, the
// lists asked for, the timings.
void print_summary(FILE* human, const DetectArgs& a, const Scene& scene, const std::vector<Object>& objects,
                   const DetectOptions& opt, const Runner& runner, const FrameResult& result, const CheckResult& check,
                   std::size_t runs) {
  print_frame_header(human, scene, objects, opt, runner, result);
  std::size_t colliding = 0, colliding_objects = 0;
  for (std::size_t i = 0; i < result.pairs.size(); ++i) {
    const PairResult& p = result.pairs[i];
    colliding += p.colliding.size();
    colliding_objects += p.is_collision() ? 1 : 0;
    print_pair(human, p, objects, opt);
    if (a.check) {
      const Score& sc = check.scores[i];
      std::fprintf(human, "  exact reference: %zu pairs; found %zu, missed %zu (miss ratio %.2f%%), false contacts %zu\n",
                   sc.exact, sc.found, sc.missed, 100.0 * sc.miss_ratio(), sc.false_contacts);
    }
    print_relation(human, p, objects, opt, a.check);
  }
  std::fprintf(human, "%s: %zu colliding triangle pairs in %zu of %zu overlapping object pairs%s\n",
               colliding_objects ? "collision" : "no collision", colliding, colliding_objects, result.pairs.size(),
               colliding && !a.list ? " (--list prints them)" : "");
  for (const PairResult& p : result.pairs) {
    if (a.list && !p.colliding.empty())
      print_index_pairs(human, p, objects, "triangle pairs", p.colliding,
                        [](const Contact& c) { return std::pair(c.tri_a, c.tri_b); });
  }
  for (const PairResult& p : result.pairs) {
    if (a.pcs && !p.pcs.empty())
      print_index_pairs(human, p, objects, "PCS", p.pcs, [](const IdPair& c) { return std::pair(c.a, c.b); });
  }
  const Timings& t = result.timings;
  std::fprintf(human, "timings (ms%s): aabb %.3f  upload %.3f  gpu %.3f  readback %.3f  cpu %.3f  total %.3f\n",
               runs > 1 ? (", median of " + std::to_string(runs)).c_str() : "", t.aabb, t.upload, t.gpu, t.readback,
               t.cpu, t.total);
  if (result.rois_peeled)
    std::fprintf(human, "  host work %.3f (total - GL waits %.3f)\n", t.total - t.gl_wait, t.gl_wait);
  if (t.gpu_timed)
    std::fprintf(human, "  GPU passes (timer queries): raster %.3f  compute %.3f (selection %.3f, coverage %.3f)  transfer %.3f%s\n",
                 t.gpu_raster, t.gpu_compute, t.gpu_select, t.gpu_cover, t.gpu_transfer,
                 t.gpu_passes_untimed
                     ? ("  (" + std::to_string(t.gpu_passes_untimed) + " passes' results impossible: left out)").c_str()
                     : "");
}

}  // namespace

int run_detect(const DetectArgs& a) {
  if (!a.json_out.empty()) check_output_path(a.json_out, "peelcd detect: --json");
  const Progress progress;
  progress.phase("peelcd detect: loading the meshes...");
  const Scene scene = detect_input(a.inputs, "peelcd detect", a.flags_on.count("self") && a.flags_on.at("self"));
  refuse_overwriting_input(a.json_out, scene_inputs(scene), "peelcd detect: --json");
  const DetectOptions opt = merged_options(scene, a);
  const std::vector<Object> objects = load_objects(scene);
  progress.phase("peelcd detect: running the frame...");
  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.gl), a.costs);
  runner.stage->set_pass_timing(a.gpu_timers);
  std::size_t runs = 0;
  const FrameResult result = run_frames(runner, objects, opt, a.repeat, runs);
  progress.clear();
  const CheckResult check = a.check ? check_pairs(result, objects, opt, std::size_t(std::max(0, a.explain_misses)))
                                    : CheckResult{};
  // The human summary: on stdout, or on stderr when the JSON goes to stdout.
  FILE* const human = a.json_out == "-" ? stderr : stdout;
  if (!a.quiet) print_summary(human, a, scene, objects, opt, runner, result, check, runs);
  if (!a.json_out.empty())
    write_output(a.json_out, to_json(result, objects, opt, a.check ? &check.scores : nullptr, runner.gl_settings()).dump(2));
  const Score& total = check.total;
  if (a.check && !a.quiet)
    std::fprintf(human, "check: %zu exact pairs, %zu missed (miss ratio %.4f%%)\n", total.exact, total.missed,
                 100.0 * total.miss_ratio());
  if (!check.misses.empty()) {  // --explain-misses: the same frame again, every layer captured
    const oracle::FrameTrace trace(*runner.detector, objects, opt);
    std::fprintf(human, "explain: the first %zu missed pair(s) (peelcd explain ... --pair A:TRI,B:TRI for the whole walk)\n",
                 check.misses.size());
    for (const oracle::PairQuery& m : check.misses)
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
    for (const PairResult& p : result.pairs) any = any || p.is_collision();
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
  Runner runner = make_runner(a.backend, merged_gl_options(scene, a.gl), a.costs);
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


std::vector<Command> add_detect_commands(CLI::App& app) {
  auto d_holder = std::make_shared<DetectArgs>();
  DetectArgs& d = *d_holder;
  CLI::App* detect = app.add_subcommand(
      "detect", "Run one frame of collision detection on a scene file or on mesh files and report the colliding "
                "triangle pairs (indices in each mesh file's triangle order)");
  detect->add_option("input", d.inputs, "A scene JSON file, or two or more mesh files (OBJ, PLY, STL, glTF, ...: "
                                        "identity transforms, named by their file names, default options)")
      ->required();
  add_frame_options(detect, d);
  detect->add_option("--json", d.json_out, "Write the JSON report to FILE, or - for stdout")->check(kOutputPath);
  detect->add_flag("--list", d.list, "Print every colliding triangle pair (A's triangle, B's) after the summary");
  detect->add_flag("--pcs", d.pcs, "Print every pair's PCS (the image stage's potentially colliding ID pairs, sorted) "
                                   "after the summary: the image stage's output, to compare runs and backends");
  detect->add_flag("--status", d.status,
                   "Exit status for scripts, as grep's: 0 when anything collides, 1 when nothing does (2 bad input, 3 --max-miss)");
  detect->add_option("--repeat", d.repeat, "Run the frame N times and report median timings")
      ->check(kPositive);
  detect->add_flag("--gpu-timers", d.gpu_timers,
                   "Time the image stage's GPU passes with GL timer queries: raster (draws), compute (dispatches) "
                   "and transfer (uploads, clears, copies), printed with the timings and in the JSON");
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

  auto ex_holder = std::make_shared<DetectArgs>();
  DetectArgs& ex = *ex_holder;
  auto explain_args_holder = std::make_shared<ExplainArgs>();
  ExplainArgs& explain_args = *explain_args_holder;
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

  return {{detect, [d_holder] { return run_detect(*d_holder); }},
          {explain, [ex_holder, explain_args_holder] { return run_explain(*ex_holder, *explain_args_holder); }}};
}
}  // namespace peelcd::cli
