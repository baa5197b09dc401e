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

}  // namespace peelcd::oracle
