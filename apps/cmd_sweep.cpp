// peelcd sweep (the command line; shared parts in cli.h).
#include "cli.h"

#include <algorithm>
#include <cstring>
#include "peelcd/eval/sweep.h"

namespace peelcd::cli {

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

// Runs the plot script on a sweep CSV (Debian's interpreter, where python3-matplotlib lives,
// unless PYTHON names another).
void plot_sweep(const std::string& csv_path, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const char* python = std::getenv("PYTHON");
  const std::string py = python ? python : (std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  const std::string cmd = "'" + py + "' '" + data_dir("scripts") + "/plot_sweep.py' '" + csv_path + "' '" + dir + "'";
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
  int width = int(std::strlen("configuration"));  // the labels' column as wide as the longest
  for (const SweepConfig& c : configs) width = std::max(width, int(c.label().size()));
  std::printf("%-*s %9s %9s %9s %6s %11s %6s %11s %11s\n", width, "configuration", "avg miss", "max miss", "min miss",
              "false", "candidates", "eff", "median ms", "mean ms");
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const SweepSummary s = summarize(rows, c);
    std::printf("%-*s %8.2f%% %8.2f%% %8.2f%% %6zu %11.0f %5.1f%% %11.2f %11.2f\n", width, configs[c].label().c_str(),
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


std::vector<Command> add_sweep_commands(CLI::App& app) {
  auto sw_holder = std::make_shared<SweepArgs>();
  SweepArgs& sw = *sw_holder;
  CLI::App* sweep = app.add_subcommand(
      "sweep", "Measure accuracy and run time over view directions and configurations against the "
               "exact reference; prints a summary per configuration (average/max/min miss ratio)");
  sweep->add_option("scene", sw.scene, "Scene JSON file");
  sweep->add_option("--shard", sw.shard, "Run the K-th of N deterministic slices of the view directions (K/N, "
                                         "e.g. 3/8); join the shards' CSVs with: peelcd sweep merge");
  auto sm_holder = std::make_shared<SweepMergeArgs>();
  SweepMergeArgs& sm = *sm_holder;
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
  add_backend_option(sweep, sw.backend, true);
  sweep->add_option("--csv", sw.csv, "Write one row per (configuration, view) to FILE, or - for stdout")->check(kOutputPath);
  sweep->add_option("--plot", sw.plot, "Write heat maps and the run-time-against-miss-ratio plot to DIR (matplotlib)")->check(kOutputPath);

  return {{sweep_merge, [sm_holder] { return run_sweep_merge(*sm_holder); }},
          {sweep,
           [sw_holder] {
             if (sw_holder->scene.empty())
               throw InputError("peelcd sweep: a scene file is required (or: peelcd sweep merge CSV...)");
             return run_sweep_command(*sw_holder);
           }}};
}
}  // namespace peelcd::cli
