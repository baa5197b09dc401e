#include "peelcd/oracle/golden.h"

#include "peelcd/io/error.h"
#include "peelcd/io/output.h"

#include <algorithm>
#include <filesystem>

namespace peelcd::oracle {

namespace fs = std::filesystem;

std::vector<std::string> golden_case_names(const std::string& dir) {
  std::vector<std::string> all;
  if (!fs::is_directory(dir)) throw InputError("peelcd golden: '" + dir + "' is not a folder");
  for (const auto& e : fs::directory_iterator(dir))
    if (fs::exists(e.path() / "case.json")) all.push_back(e.path().filename().string());
  std::sort(all.begin(), all.end());
  if (all.empty()) throw InputError("peelcd golden: no cases (folders with a case.json) in '" + dir + "'");
  return all;
}

std::string golden_case_scene(const std::string& dir, const std::string& name) {
  const std::string path = dir + "/" + name + "/case.json";
  if (!fs::exists(path)) throw InputError("peelcd golden: unknown case \"" + name + "\" (no " + path + ")");
  return path;
}

std::string golden_case_expected(const std::string& dir, const std::string& name) {
  return dir + "/" + name + "/expected";
}

void record_golden_case(const Dump& dump, const std::string& dir, const std::string& name) {
  const std::string expected = golden_case_expected(dir, name), fresh = expected + ".new";
  std::error_code ec;
  const DeferSignals hold;  // Ctrl-C: this case's goldens are replaced whole, or not at all
  fs::remove_all(fresh, ec);
  write_dump(dump, fresh, false);
  fs::remove_all(expected);
  fs::rename(fresh, expected);
}

std::vector<std::string> golden_shard(const std::vector<std::string>& cases, std::size_t shard, std::size_t shards) {
  std::vector<std::string> out;
  for (std::size_t i = shard; i < cases.size(); i += shards) out.push_back(cases[i]);
  return out;
}

Comparison compare_production(const Dump& expected, const FrameResult& frame, bool conservative) {
  using Pair = std::array<std::uint32_t, 2>;
  Comparison c;
  const auto list = [](const std::vector<Pair>& v) {
    std::string s;
    for (std::size_t k = 0; k < v.size() && k < 8; ++k) s += " (" + std::to_string(v[k][0]) + "," + std::to_string(v[k][1]) + ")";
    if (v.size() > 8) s += " ...";
    return s;
  };
  for (const DumpPair& pe : expected.pairs) {
    const auto it = std::find_if(frame.pairs.begin(), frame.pairs.end(), [&](const PairResult& p) {
      return p.object_a == pe.object_a && p.object_b == pe.object_b;
    });
    if (it == frame.pairs.end()) {
      c.failures.push_back(pe.dir + ": no such object pair in the production path's frame");
      continue;
    }
    std::vector<Pair> found;
    for (const Contact& k : it->colliding) found.push_back({k.tri_a, k.tri_b});
    std::sort(found.begin(), found.end());
    std::vector<Pair> missing, extra;
    std::set_difference(pe.colliding.begin(), pe.colliding.end(), found.begin(), found.end(), std::back_inserter(missing));
    std::set_difference(found.begin(), found.end(), pe.colliding.begin(), pe.colliding.end(), std::back_inserter(extra));
    if (conservative) {
      if (!missing.empty())
        c.failures.push_back(pe.dir + ": " + std::to_string(missing.size()) + " golden colliding pairs missing:" + list(missing));
      if (!extra.empty())
        c.failures.push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" + list(extra));
    } else {
      const auto& reference = pe.has_reference ? pe.reference : pe.colliding;
      const auto misses = [&](const std::vector<Pair>& v) {
        std::vector<Pair> m;
        std::set_difference(reference.begin(), reference.end(), v.begin(), v.end(), std::back_inserter(m));
        return m.size();
      };
      const std::size_t golden_misses = misses(pe.colliding), actual_misses = misses(found);
      const std::size_t slack = hardware_miss_slack(reference.size());
      const std::string counts = std::to_string(actual_misses) + " of " + std::to_string(reference.size()) +
                                 " reference pairs missed, golden " + std::to_string(golden_misses) + ", slack " +
                                 std::to_string(slack);
      if (actual_misses > golden_misses + slack)
        c.failures.push_back(pe.dir + ": " + counts + "; golden pairs missing:" + list(missing));
      else if (!missing.empty() || !extra.empty())
        c.notes.push_back(pe.dir + ": " + counts + " (within the bound)");
    }
    if (it->pcs.size() != pe.pcs.size())
      c.notes.push_back(pe.dir + ": " + std::to_string(it->pcs.size()) + " PCS (golden, one view at a time: " +
                        std::to_string(pe.pcs.size()) + ")");
  }
  if (frame.views_host_resolved)
    c.notes.push_back(std::to_string(frame.views_host_resolved) + " views resolved on the host (a texel deeper than the GPU resolve takes)");
  if (frame.gl_deep_texels)
    c.notes.push_back(std::to_string(frame.gl_deep_texels) + " deep texels split over GPU invocations");
  return c;
}

}  // namespace peelcd::oracle
