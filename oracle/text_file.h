#pragma once
// Text files of a dump or a report, written whole, and the HTML pages' text (internal to the
// oracle).
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

// `in` as HTML text or an attribute's value: <, >, & and " as entities.
inline std::string html_escape(const std::string& in) {
  std::string out;
  for (const char c : in) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

}  // namespace peelcd::oracle
