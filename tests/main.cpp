// The tests' main. PEELCD_TEST_BACKEND names a GL driver stack for the GL tests; the stacks that
// need Mesa's environment get it here, before anything loads a GL driver:
//   egl-llvmpipe  EGL with LIBGL_ALWAYS_SOFTWARE=1 (llvmpipe even where a GPU is)
//   egl-zink      EGL over zink (OpenGL on Vulkan) over lavapipe: MESA_LOADER_DRIVER_OVERRIDE=zink,
//                 LIBGL_ALWAYS_SOFTWARE=1 and a private XDG_RUNTIME_DIR
//
// PEELCD_TEST_FP_TRAPS (test_core's main, debug builds only: NDEBUG unset): floating-point traps
// on (invalid operation, division by zero, overflow: SIGFPE at the faulting instruction), as
// libigl's test main does, so a NaN or an infinity the core makes by accident stops the test
// where it is made. Test cases tagged [nonfinite] feed NaN, infinities or values near the
// double range on purpose (bad-input tests, the exact predicates' extreme cases): traps off there.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdlib>
#include <string>

#if PEELCD_TEST_FP_TRAPS && !defined(NDEBUG)
#include <fenv.h>

#include <algorithm>

namespace {
struct FpTraps : Catch::TestEventListenerBase {
  using TestEventListenerBase::TestEventListenerBase;
  void testCaseStarting(Catch::TestCaseInfo const& info) override {
    feclearexcept(FE_ALL_EXCEPT);
    const bool exempt = std::find(info.tags.begin(), info.tags.end(), "nonfinite") != info.tags.end();
    if (exempt) fedisableexcept(FE_ALL_EXCEPT);
    else feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
  }
  void testCaseEnded(Catch::TestCaseStats const&) override { fedisableexcept(FE_ALL_EXCEPT); }
};
}  // namespace
CATCH_REGISTER_LISTENER(FpTraps)
#endif

int main(int argc, char* argv[]) {
  const char* stack = std::getenv("PEELCD_TEST_BACKEND");
  const std::string s = stack ? stack : "";
  if (s == "egl-llvmpipe" || s == "egl-zink") setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);
  if (s == "egl-zink") {
    setenv("MESA_LOADER_DRIVER_OVERRIDE", "zink", 1);
    if (!std::getenv("XDG_RUNTIME_DIR")) {
      static char dir[] = "/tmp/peelcd-xdg-XXXXXX";
      if (mkdtemp(dir)) setenv("XDG_RUNTIME_DIR", dir, 1);
    }
  }
  return Catch::Session().run(argc, argv);
}
