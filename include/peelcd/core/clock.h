#pragma once
// The one stopwatch of peelcd's timings (FrameResult::timings, the benchmarks): a steady clock
// and the milliseconds since one of its time points.
#include <chrono>

namespace peelcd {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace peelcd
