#include "peelcd/eval/sweep.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/exact/reference.h"

#include <algorithm>
#include <map>
#include <sstream>

namespace peelcd {

std::string SweepConfig::label() const {
  std::ostringstream s;
  s << resolution << " " << to_string(ids) << " " << mode();
  if (mode() != "conservative") s << " slope=" << slope;  // point sampling's; the conservative stage has none
  s << " views=" << views << " cull=" << to_string(cull);
  return s.str();
}

std::string SweepConfig::mode() const {
  if (conservative) return "conservative";
  if (peel == PeelMode::full) return "full";
  return slope == 0.0 ? "paper" : "alternate";
}

std::vector<std::pair<double, double>> sweep_directions(double theta_step, double phi_step) {
  if (!(theta_step > 0) || !(phi_step > 0)) throw std::invalid_argument("peelcd::sweep_directions(): steps must be positive");
  std::vector<std::pair<double, double>> out;
  out.emplace_back(0.0, -90.0);
  for (double phi = -90.0 + phi_step; phi < 90.0 - 1e-9; phi += phi_step)
    for (double theta = 0.0; theta < 360.0 - 1e-9; theta += theta_step) out.emplace_back(theta, phi);
  out.emplace_back(0.0, 90.0);
  return out;
}

std::vector<SweepRow> run_sweep(Detector& detector, const std::vector<Object>& objects,
                                const std::vector<SweepConfig>& configs,
                                const std::vector<std::pair<double, double>>& directions,
                                const std::function<void(std::size_t, std::size_t)>& progress) {
  // The exact reference does not depend on the view: once per object pair.
  std::vector<Aabb> boxes;
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>> exact;
  for (const auto& p : overlapping_pairs(boxes))
    exact[p] = exact_colliding_pairs(objects[p.first].mesh, objects[p.second].mesh);

  std::vector<SweepRow> rows;
  const std::size_t total = configs.size() * directions.size();
  for (std::size_t c = 0; c < configs.size(); ++c) {
    DetectOptions opt;
    opt.stage = Stage::image;  // a sweep measures the image stage
    opt.roll = 0.0;  // directions turn the paper's frame
    opt.conservative = configs[c].conservative;
    opt.resolution = configs[c].resolution;
    opt.ids = configs[c].ids;
    opt.peel = configs[c].peel;
    opt.slope = configs[c].slope;
    opt.views = configs[c].views;
    opt.cull = configs[c].cull;
    for (const auto& [theta, phi] : directions) {
      opt.theta = theta;
      opt.phi = phi;
      const FrameResult f = detector.detect(objects, opt);
      SweepRow row;
      row.config = c;
      row.theta = theta;
      row.phi = phi;
      row.timings = f.timings;
      for (const PairResult& p : f.pairs) {
        const Score sc = score_contacts(exact.at({p.object_a, p.object_b}), p.colliding);
        row.exact += sc.exact;
        row.found += sc.found;
        row.false_contacts += sc.false_contacts;
        row.pcs += p.pcs_count;
        row.candidates += p.candidates;
        row.layers = std::max(row.layers, p.layers);
        row.passes += p.passes;
      }
      rows.push_back(row);
      if (progress) progress(rows.size(), total);
    }
  }
  return rows;
}

SweepSummary summarize(const std::vector<SweepRow>& rows, std::size_t config) {
  SweepSummary s;
  std::vector<double> totals;
  s.min_miss = 1.0;
  for (const SweepRow& r : rows) {
    if (r.config != config) continue;
    ++s.views;
    s.avg_miss += r.miss_ratio();
    s.max_miss = std::max(s.max_miss, r.miss_ratio());
    s.min_miss = std::min(s.min_miss, r.miss_ratio());
    s.false_contacts += r.false_contacts;
    s.mean_candidates += double(r.candidates);
    s.mean_efficiency += r.efficiency();
    s.mean_total_ms += r.timings.total;
    totals.push_back(r.timings.total);
  }
  if (!s.views) return SweepSummary{};
  s.avg_miss /= double(s.views);
  s.mean_candidates /= double(s.views);
  s.mean_efficiency /= double(s.views);
  s.mean_total_ms /= double(s.views);
  std::sort(totals.begin(), totals.end());
  s.median_total_ms = totals.size() % 2 ? totals[totals.size() / 2]
                                        : 0.5 * (totals[totals.size() / 2 - 1] + totals[totals.size() / 2]);
  return s;
}

std::string sweep_csv(const std::vector<SweepRow>& rows, const std::vector<SweepConfig>& configs,
                      const std::string& sweep, const std::string& shard) {
  std::ostringstream out;
  out << "config,resolution,ids,mode,slope,views,theta,phi,exact,found,missed,miss_ratio,false_contacts,pcs,"
         "candidates,efficiency,layers,passes,aabb_ms,upload_ms,gpu_ms,readback_ms,cpu_ms,total_ms,cull,sweep,shard\n";
  for (const SweepRow& r : rows) {
    const SweepConfig& c = configs[r.config];
    out << '"' << c.label() << "\"," << c.resolution << ',' << to_string(c.ids) << ','
        << c.mode() << ',' << c.slope << ',' << c.views << ',' << r.theta
        << ',' << r.phi << ',' << r.exact << ',' << r.found << ',' << (r.exact - r.found) << ','
        << r.miss_ratio() << ',' << r.false_contacts << ',' << r.pcs << ',' << r.candidates << ','
        << r.efficiency() << ',' << r.layers << ',' << r.passes << ',' << r.timings.aabb << ','
        << r.timings.upload << ',' << r.timings.gpu << ',' << r.timings.readback << ',' << r.timings.cpu << ','
        << r.timings.total << ',' << to_string(c.cull) << ',' << sweep << ',' << shard << '\n';
  }
  return out.str();
}

}  // namespace peelcd
