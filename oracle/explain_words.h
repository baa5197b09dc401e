#pragma once
// Small wording helpers shared by explain's trace (explain.cpp) and its reports
// (explain_report.cpp). Private to the oracle component.
#include <cstdint>
#include <cstdio>
#include <string>

namespace peelcd::oracle::words {

inline std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}
inline std::string g(double v) { return fmt("%.6g", v); }
inline std::string object_word(std::uint32_t object) { return object == 0 ? "A" : "B"; }

}  // namespace peelcd::oracle::words
