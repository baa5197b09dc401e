// peelcd sweep (the command line; shared parts in cli.h).
#include "cli.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <map>
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
  std::string sweep, sweep_file;                           // the sweep every row must belong to
  std::map<std::size_t, std::string> shard_files;          // shard K -> its file
  std::size_t shard_count = 0;                             // N of "K/N"
  std::string shard_count_file;
  for (const std::string& path : a.inputs) {
    std::ifstream in(path);
    if (!in) throw InputError("peelcd sweep merge: '" + path + "': cannot read it");
    std::string first, line;
    if (!std::getline(in, first) || first.rfind("config,", 0) != 0)
      throw InputError("peelcd sweep merge: '" + path + "': not a sweep CSV (no \"config,...\" header)");
    if (first.size() < 12 || first.compare(first.size() - 12, 12, ",sweep,shard") != 0)
      throw InputError("peelcd sweep merge: '" + path + "': no sweep and shard columns (written by an older peelcd): "
                       "run the sweep again");
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
      // The last two columns: the sweep's identity and the shard.
      const std::string shard_text = cols.back(), this_sweep = cols[cols.size() - 2];
      if (sweep.empty()) {
        sweep = this_sweep;
        sweep_file = path;
      } else if (this_sweep != sweep) {
        throw InputError("peelcd sweep merge: '" + path + "' is of the sweep " + this_sweep + ", '" + sweep_file +
                         "' of " + sweep + ": CSVs of different sweeps (scene, meshes, view steps or configurations)");
      }
      std::size_t k = 0, n = 0;
      if (std::sscanf(shard_text.c_str(), "%zu/%zu", &k, &n) != 2 || k < 1 || k > n)
        throw InputError(where + ": malformed shard \"" + shard_text + "\"");
      if (shard_count == 0) {
        shard_count = n;
        shard_count_file = path;
      } else if (n != shard_count) {
        throw InputError("peelcd sweep merge: '" + path + "' is a shard of " + std::to_string(n) + ", '" +
                         shard_count_file + "' of " + std::to_string(shard_count));
      }
      if (const auto [it, fresh] = shard_files.emplace(k, path); !fresh && it->second != path)
        throw InputError("peelcd sweep merge: shard " + std::to_string(k) + "/" + std::to_string(n) + " is in both '" +
                         it->second + "' and '" + path + "'");
      const std::string label = line.substr(1, close - 1);
      const auto it = std::find(labels.begin(), labels.end(), label);
      const std::size_t config = std::size_t(it - labels.begin());
      if (it == labels.end()) labels.push_back(label);
      rows.push_back({config, theta, phi, line, path});
    }
  }
  // Every shard of the sweep, or the merge would be partial.
  std::string missing;
  for (std::size_t k = 1; k <= shard_count; ++k)
    if (!shard_files.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  if (!missing.empty())
    throw InputError("peelcd sweep merge: shard(s) " + missing + " of " + std::to_string(shard_count) +
                     " missing: the merged sweep would be incomplete");
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

// A sweep's identity: the scene file's name and a 64-bit FNV-1a hash of what decides its rows
// (the scene file's and its meshes' bytes, the view steps, the configurations), so that shards
// run apart (other machines, other paths) are known to belong together.
std::string sweep_identity(const SweepArgs& a, const Scene& scene, const std::vector<SweepConfig>& configs) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&](const std::string& bytes) {
    for (const unsigned char ch : bytes) h = (h ^ ch) * 1099511628211ull;
  };
  for (const std::string& path : scene_inputs(scene)) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    mix(ss.str());
  }
  char steps[64];
  std::snprintf(steps, sizeof steps, "%.17g/%.17g", a.theta_step, a.phi_step);
  mix(steps);
  for (const SweepConfig& c : configs) mix(c.label());
  char id[32];
  std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(h));
  return std::filesystem::path(a.scene).filename().string() + ":" + id;
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
  if (!csv_path.empty())
    write_output(csv_path, sweep_csv(rows, configs, sweep_identity(a, scene, configs),
                                     std::to_string(shard + 1) + "/" + std::to_string(shards)));
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
