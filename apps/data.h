#pragma once
// Where the command line finds its data (the fixture meshes of test1/test2/calibrate, the golden
// cases, the plot scripts), so that an installed peelcd runs without the build's source tree:
//   1. $PEELCD_DATA_DIR, when set: a folder holding fixtures/ and scripts/;
//   2. run from its build tree (the executable beside the build's own): the source tree;
//   3. installed: <prefix>/share/peelcd beside <prefix>/bin/peelcd (cmake --install).
// A command that needs a data folder and finds none says which places it tried.
#include "peelcd/io/error.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace peelcd::cli {

// The folder `relative` (e.g. "fixtures/meshes") under the first data root that has it.
inline std::string data_dir(const std::string& relative) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::string tried;
  const auto has = [&](const fs::path& root) {
    tried += (tried.empty() ? "" : ", ") + (root / relative).string();
    return fs::is_directory(root / relative, ec);
  };
  if (const char* env = std::getenv("PEELCD_DATA_DIR"); env && *env) {
    if (has(env)) return (fs::path(env) / relative).string();
    throw InputError("peelcd: PEELCD_DATA_DIR is set, but '" + (fs::path(env) / relative).string() +
                     "' is not a folder");
  }
  const fs::path exe = fs::canonical("/proc/self/exe", ec);
  const fs::path exe_dir = ec ? fs::path() : exe.parent_path();
  if (!exe_dir.empty() && fs::equivalent(exe_dir, PEELCD_BUILD_BIN_DIR, ec) && has(PEELCD_SOURCE_DIR))
    return (fs::path(PEELCD_SOURCE_DIR) / relative).string();
  if (!exe_dir.empty() && has(exe_dir.parent_path() / "share" / "peelcd"))
    return (exe_dir.parent_path() / "share" / "peelcd" / relative).string();
  throw InputError("peelcd: cannot find its data folder '" + relative + "' (tried " + tried +
                   "); set PEELCD_DATA_DIR to a folder holding fixtures/ and scripts/");
}

// Throws InputError ("<what> 'out': it is inside peelcd's own data ...") when the output `out`
// would land in the data folder's fixtures (the built-in scenes' meshes, the goldens): an output
// never overwrites the data a command reads. Checked before any work.
inline void refuse_overwriting_data(const std::string& out, const std::string& what) {
  namespace fs = std::filesystem;
  if (out.empty() || out == "-") return;
  std::string fixtures;
  try {
    fixtures = data_dir("fixtures");
  } catch (const InputError&) {
    return;  // no data folder: nothing of it to overwrite
  }
  std::error_code ec;
  const fs::path data = fs::weakly_canonical(fixtures, ec), target = fs::weakly_canonical(out, ec);
  if (ec) return;
  const auto [d, t] = std::mismatch(data.begin(), data.end(), target.begin(), target.end());
  if (d == data.end())
    throw InputError(what + " '" + out + "': it is inside peelcd's own data ('" + data.string() +
                     "', which the built-in scenes read): write it elsewhere");
}

}  // namespace peelcd::cli
