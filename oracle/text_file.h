#pragma once
// Text files of a dump or a report, written whole (internal to the oracle).
#include "peelcd/io/error.h"

#include <filesystem>
#include <fstream>
#include <string>

namespace peelcd::oracle {

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out.flush()) throw InputError("peelcd: cannot write '" + path.string() + "'");
}

}  // namespace peelcd::oracle
