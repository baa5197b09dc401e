#pragma once
// Accuracy sweeps: every configuration x every view direction of a scene, each frame scored
// against the exact all-pairs reference (every miss and every false contact counts).
#include "peelcd/core/frame.h"
#include "peelcd/core/image/detector.h"

#include <functional>
#include <string>
#include <vector>

namespace peelcd {

struct SweepConfig {
  int resolution = 256;
  IdMode ids = IdMode::paper;
  PeelMode peel = PeelMode::full;
  double slope = 1.0;
  int views = 1;
  Cull cull = Cull::contact;
  bool conservative = false;  // the conservative image stage (ids, peel and slope do not apply)
  std::string label() const;  // e.g. "256 paper full slope=1 views=1 cull=contact"
  std::string mode() const;   // paper (alternate, slope 0), alternate, full or conservative
};

// theta over [0, 360) by theta_step, phi over [-90, 90] by phi_step, each pole once.
std::vector<std::pair<double, double>> sweep_directions(double theta_step, double phi_step);

struct SweepRow {
  std::size_t config = 0;  // index into the configurations
  double theta = 0, phi = 0;
  std::size_t exact = 0, found = 0, false_contacts = 0, pcs = 0, candidates = 0;
  int layers = 0, passes = 0;
  Timings timings;
  double miss_ratio() const { return exact ? double(exact - found) / double(exact) : 0.0; }
  double efficiency() const { return candidates ? double(found) / double(candidates) : 0.0; }
};

struct SweepSummary {
  double avg_miss = 0, max_miss = 0, min_miss = 0;
  double median_total_ms = 0, mean_total_ms = 0;
  std::size_t false_contacts = 0, views = 0;
  double mean_candidates = 0, mean_efficiency = 0;
};

// Runs every configuration over every direction. Every object pair with an overlapping box is
// scored and summed into one row per frame. `progress(done, total)` is called after each frame.
std::vector<SweepRow> run_sweep(Detector& detector, const std::vector<Object>& objects,
                                const std::vector<SweepConfig>& configs,
                                const std::vector<std::pair<double, double>>& directions,
                                const std::function<void(std::size_t, std::size_t)>& progress = {});

SweepSummary summarize(const std::vector<SweepRow>& rows, std::size_t config);

// CSV with a header line; one row per (configuration, direction).
// `sweep`: the sweep's identity (its scene, meshes, view steps and configurations; sweep merge
// joins only CSVs of one sweep), `shard`: "K/N" ("1/1" unsharded); both a column of every row.
std::string sweep_csv(const std::vector<SweepRow>& rows, const std::vector<SweepConfig>& configs,
                      const std::string& sweep = "", const std::string& shard = "1/1");

}  // namespace peelcd
