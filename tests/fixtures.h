#pragma once
// Helpers that several test files share (each file's own helpers stay file-local; the larger test
// programs compile several files to one translation unit, so a helper two files need lives here).
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"

#include <memory>

namespace peelcd::test {

// One detector over the CPU image stage for the test program.
inline Detector& cpu_detector() {
  static Detector d(std::make_shared<CpuImageStage>());
  return d;
}

}  // namespace peelcd::test
