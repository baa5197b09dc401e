#pragma once
// The long sweeps of the suite (geometry classes, poses, meshes, each against an exact reference)
// run every case by default. PEELCD_TEST_STRIDE=N runs every Nth case of them (the first, then
// each Nth after it): the sanitizer stage sets it (scripts/sanitize.sh), where a case costs about
// ten times as much, so that the same code runs instrumented on fewer inputs; the plain build
// runs them all.
#include <cstddef>
#include <cstdlib>

namespace peelcd::test {

inline std::size_t stride() {
  static const std::size_t s = [] {
    const char* env = std::getenv("PEELCD_TEST_STRIDE");
    const long v = env ? std::strtol(env, nullptr, 10) : 1;
    return v > 1 ? std::size_t(v) : std::size_t(1);
  }();
  return s;
}

// Case i of a sweep is left out under the stride.
inline bool stride_skips(std::size_t i) { return i % stride() != 0; }

}  // namespace peelcd::test
