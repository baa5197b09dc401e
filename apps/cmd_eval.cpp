// peelcd classes and calibrate (the command line; shared parts in cli.h).
#include "cli.h"
#include "peelcd/eval/calibrate.h"
#include "peelcd/core/world/world.h"
#include "peelcd/eval/classes.h"

#include <algorithm>
#include <cmath>
#include <ctime>

namespace peelcd::cli {

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
  std::vector<GeometryClass> classes = geometry_classes(a.grid);
  for (GeometryClass& g : self_classes()) classes.push_back(std::move(g));  // Object::self set
  if (!a.only.empty() && std::none_of(classes.begin(), classes.end(), [&](const GeometryClass& g) { return g.name == a.only; })) {
    std::string names;
    for (const GeometryClass& g : classes) names += (names.empty() ? "" : ", ") + g.name;
    throw InputError("peelcd classes: --class: no class named \"" + a.only + "\" (the classes: " + names + ")");
  }
  Runner runner = make_runner(a.backend, gl::GlOptions{});
  std::printf("peelcd classes: %s (%s); median of %d frames; grid %dx%d\n", runner.backend().c_str(),
              runner.renderer().c_str(), a.repeat, a.grid, a.grid);
  std::printf("%-28s %-32s %7s %7s %7s %9s %9s %11s %9s\n", "class", "configuration", "exact", "found", "missed",
              "miss %", "len miss%", "candidates", "ms");
  for (const GeometryClass& g : classes) {
    if (!a.only.empty() && g.name != a.only) continue;
    for (const auto& [name, opt] : class_configs()) {
      const ClassRow r = measure_class(*runner.detector, g, name, opt, a.repeat);
      std::printf("%-28s %-32s %7zu %7zu %7zu %9.3f %9.3f %11zu %9.2f\n", g.name.c_str(), name.c_str(), r.exact, r.found,
                  r.missed, 100.0 * r.miss_ratio(), 100.0 * r.missed_length_share(), r.candidates, r.median_ms);
      std::fflush(stdout);
    }
  }
  if (!a.only.empty()) return 0;
  // Containment and volume: the relation against the construction's, the volume against CGAL's
  // exact corefinement (docs/design.md).
  DetectOptions volume;
  volume.volume = true;
  std::printf("\ncontainment and volume (default configuration with --volume; exact volume: CGAL corefinement)\n");
  std::printf("%-28s %-11s %-11s %12s %12s %12s %10s %8s %9s\n", "class", "expected", "found", "volume", "+- estimate",
              "exact", "error", "rel %", "ms");
  for (const ContainmentClass& c : containment_classes()) {
    const ContainmentRow r = measure_containment(*runner.detector, c, volume, a.repeat);
    std::printf("%-28s %-11s %-11s %12.6g %12.2g %12.6g %10.2g %8.4f %9.2f%s\n", c.scene.name.c_str(), to_string(r.expected),
                r.pair ? to_string(r.found) : "(no pair)", r.volume, r.error_bound, r.exact_volume, r.error(),
                100.0 * r.relative_error(), r.median_ms, r.error() > r.error_bound ? "  ERROR ABOVE ITS ESTIMATE" : "");
    std::fflush(stdout);
  }
  return 0;
}

struct CalibrateArgs {
  std::string backend = kDefaultBackend;
  int repeat = 5;
  std::vector<int> budgets = {128, 512};
  std::vector<int> large = {72, 144, 288};  // crossing spheres' stacks (20k, 82k, 330k triangles each)
  std::string write_costs;  // the fitted models into this file (peelcd/io/costs.h)
};

int run_calibrate(const CalibrateArgs& a) {
  if (!a.write_costs.empty()) {  // before any work: never onto the meshes calibrate reads
    check_output_path(a.write_costs, "peelcd calibrate: --write-costs");
    refuse_overwriting_data(a.write_costs, "peelcd calibrate: --write-costs");
  }
  Runner runner = make_runner(a.backend, gl::GlOptions{});
  std::printf("peelcd calibrate: %s (%s); median of %d frames per stage\n", runner.backend().c_str(),
              runner.renderer().c_str(), a.repeat);
  const Calibration cal = calibrate(*runner.detector, data_dir("fixtures/meshes"), a.budgets, a.repeat);
  std::printf("%-28s %9s %6s %10s %10s %9s %9s %7s\n", "scene", "triangles", "tile", "image ms", "exact ms",
              "image cand", "exact cand", "faster");
  for (const CalibrationRow& r : cal.rows)
    std::printf("%-28s %9zu %6d %10.3f %10.3f %9zu %9zu %7s\n", r.scene.c_str(), r.triangles, r.tile, r.image_ms, r.exact_ms,
                r.image_candidates, r.exact_candidates, r.image_ms < r.exact_ms ? "image" : "exact");
  const StageCost in_image = runner.stage->router_image_cost(), in_exact = runner.stage->router_exact_cost();
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
  // The fitted models into a file the router loads (--costs, $PEELCD_COSTS, Python's costs=).
  CostModels fitted;
  fitted.image = cal.image;
  fitted.exact = cal.exact;
  fitted.exact.scan_us = in_exact.scan_us;  // the scan's term: refined below from the large meshes
  fitted.backend = runner.backend();
  fitted.renderer = runner.renderer();
  const auto write_costs = [&] {
    if (a.write_costs.empty()) return;
    char date[16];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
    write_cost_models(a.write_costs, fitted, date);
    std::printf("cost models written to %s (peelcd detect --costs %s, or PEELCD_COSTS=%s)\n", a.write_costs.c_str(),
                a.write_costs.c_str(), a.write_costs.c_str());
  };
  // The GL stage's conservative coverage: the rasterizer against the compute pass (the same
  // layers), timed in turns; the one faster on the World's batched frames goes into the file
  // (GlOptions::coverage auto).
  if (runner.gl) {
    const int budget = *std::max_element(a.budgets.begin(), a.budgets.end());
    const bool timing = runner.stage->pass_timing();
    runner.stage->set_pass_timing(true);
    const auto use = [&](int k) {
      gl::GlOptions o = runner.gl_options;
      o.coverage = k == 0 ? Coverage::raster : Coverage::compute;
      runner.gl->set_options(o);
    };
    const std::vector<VariantRow> rows = time_variants(*runner.detector, data_dir("fixtures/meshes"), budget, a.repeat, 2, use);
    const std::vector<VariantRow> world_rows = time_world_variants(*runner.detector, a.repeat, 2, use);
    runner.gl->set_options(runner.gl_options);
    runner.stage->set_pass_timing(timing);
    std::printf("\nconservative coverage (ms: the frame API's image stage at budget %d, the World's frame; and its GPU "
                "passes' ms by timer queries; medians, in turns):\n", budget);
    std::printf("%-30s %10s %10s %10s %10s\n", "scene", "raster", "compute", "raster GPU", "compute GPU");
    // Geometric means of compute / raster: every scene weighs the same, whatever its size. The
    // choice is the World's frames' (its image route draws many pairs in one batch, as the
    // frame API's multi-pair frames do; the frame API's one-pair scenes are printed beside).
    const auto geomean = [](const std::vector<VariantRow>& rs) {
      double log_ratio = 0.0;
      std::size_t timed = 0;
      for (const VariantRow& r : rs)
        if (r.ms[0] > 0.0 && r.ms[1] > 0.0) {
          log_ratio += std::log(r.ms[1] / r.ms[0]);
          ++timed;
        }
      return std::make_pair(timed ? std::exp(log_ratio / double(timed)) : 1.0, timed);
    };
    for (const auto* rs : {&rows, &world_rows})
      for (const VariantRow& r : *rs)
        std::printf("%-30s %10.3f %10.3f %10.3f %10.3f\n", r.scene.c_str(), r.ms[0], r.ms[1], r.gpu_ms[0], r.gpu_ms[1]);
    const auto [one_pair, one_pair_n] = geomean(rows);
    const auto [world, world_n] = geomean(world_rows);
    fitted.coverage = world < 1.0 ? "compute" : "raster";
    std::printf("coverage: compute / raster %.3f on the World's frames (geometric mean over %zu scenes; %.3f over the "
                "frame API's %zu one-pair scenes): %s (--coverage auto follows the file)\n",
                world, world_n, one_pair, one_pair_n, fitted.coverage.c_str());
  }
  std::vector<int> large_stacks;
  for (const int n : a.large)
    if (n >= 3) large_stacks.push_back(n);
  if (large_stacks.empty()) {
    write_costs();
    return 0;
  }
  // Large meshes: the predictions against the frames, both APIs (two crossing rigid spheres).
  const std::vector<LargeMeshRow> large = calibrate_large_meshes(*runner.detector, large_stacks, a.repeat);
  std::printf("\nlarge meshes (two crossing rigid spheres; stage auto; median of %d frames after an untimed one):\n", a.repeat);
  std::printf("%6s %10s %8s | %12s %10s %6s | %10s %12s %10s %6s %10s\n", "stacks", "triangles", "kept", "frame pred",
              "frame ms", "ratio", "candidates", "World pred", "narrow ms", "ratio", "World ms");
  double scan_num = 0.0, scan_den = 0.0;
  for (const LargeMeshRow& r : large) {
    std::printf("%6d %10zu %8zu | %12.3f %10.3f %6.2f | %10zu %12.3f %10.3f %6.2f %10.3f\n", r.stacks, r.triangles, r.kept,
                r.frame_predicted_ms, r.frame_ms, r.frame_predicted_ms > 0 ? r.frame_ms / r.frame_predicted_ms : 0.0,
                r.candidates, r.world_predicted_ms, r.world_narrow_ms,
                r.world_predicted_ms > 0 ? r.world_narrow_ms / r.world_predicted_ms : 0.0, r.world_ms);
    // The scan term, fitted: what the frame takes beyond the path's part, per triangle scanned.
    const double path = r.frame_predicted_ms - in_exact.scan_us * 1e-3 * double(r.triangles);
    scan_num += (r.frame_ms - path) * double(r.triangles) * 1e-3;
    scan_den += double(r.triangles) * 1e-3 * double(r.triangles) * 1e-3;
  }
  std::printf("(ratio: measured / predicted. frame pred: the route's prediction, scan included (scan_us %.4f in use, "
              "%.4f fitted here); World pred: its exact path's candidates x %.3f us, against its narrow phase)\n",
              in_exact.scan_us, scan_den > 0 ? scan_num / scan_den : 0.0, kWorldCandidateUs);
  if (scan_den > 0 && scan_num > 0) fitted.exact.scan_us = scan_num / scan_den;
  write_costs();
  return 0;
}


std::vector<Command> add_eval_commands(CLI::App& app) {
  auto ca_holder = std::make_shared<ClassesArgs>();
  ClassesArgs& ca = *ca_holder;
  CLI::App* classes = app.add_subcommand(
      "classes", "Measure every configuration of docs/accuracy.md on the built-in classes of geometry (crossing "
                 "and touching boxes, a floor, coincident copies, zero-area triangles, a needle, open and "
                 "self-intersecting meshes, a crowded grid) against the exact reference");
  add_backend_option(classes, ca.backend);
  classes->add_option("--repeat", ca.repeat, "Frames per measurement (median time)")->check(kPositive)
      ->capture_default_str();
  classes->add_option("--grid", ca.grid, "Side of the crowded grid (N x N spheres)")->check(CLI::Range(2, 64))
      ->capture_default_str();
  classes->add_option("--class", ca.only, "Only the class of this name");

  auto cal_holder = std::make_shared<CalibrateArgs>();
  CalibrateArgs& cal = *cal_holder;
  CLI::App* calibrate_cmd = app.add_subcommand(
      "calibrate", "Time one-ROI scenes through the image stage and the exact CPU path and fit the stage router's "
                   "cost models (docs/performance.md, \"The stage router\")");
  add_backend_option(calibrate_cmd, cal.backend);
  calibrate_cmd->add_option("--repeat", cal.repeat, "Frames per measurement (median)")->check(kPositive)
      ->capture_default_str();
  calibrate_cmd->add_option("--budgets", cal.budgets, "Texture budgets to time each scene at")
      ->check(CLI::Range(16, 16384))->capture_default_str();
  calibrate_cmd->add_option("--large", cal.large, "Large meshes: crossing spheres of these latitude bands (4 s (s - 1) "
                                                  "triangles a sphere), predictions against frames; 0: skip")
      ->check(CLI::Range(0, 2000))->capture_default_str();
  calibrate_cmd->add_option("--write-costs", cal.write_costs,
                            "Write the fitted models to FILE (JSON: backend, renderer, models), for detect --costs, "
                            "$PEELCD_COSTS and Python's costs=")
      ->check(kOutputPath);

  return {{classes, [ca_holder] { return run_classes(*ca_holder); }},
          {calibrate_cmd, [cal_holder] { return run_calibrate(*cal_holder); }}};
}
}  // namespace peelcd::cli
