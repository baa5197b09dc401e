// The tests' main. PEELCD_TEST_BACKEND names a GL driver stack for the GL tests; the stacks that
// need Mesa's environment get it here, before anything loads a GL driver:
//   egl-llvmpipe  EGL with LIBGL_ALWAYS_SOFTWARE=1 (llvmpipe even where a GPU is)
//   egl-zink      EGL over zink (OpenGL on Vulkan) over lavapipe: MESA_LOADER_DRIVER_OVERRIDE=zink,
//                 LIBGL_ALWAYS_SOFTWARE=1 and a private XDG_RUNTIME_DIR
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdlib>
#include <string>

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
