#pragma once
// EGL without a window: a GL 4.5 core context with no surface at all (EGL_KHR_surfaceless_context).
// Platforms, tried in order unless one is asked for:
//   device:      EGL_EXT_platform_device, the first device that gives a context (NVIDIA headless,
//                or Mesa's software device);
//   surfaceless: Mesa's EGL_MESA_platform_surfaceless (llvmpipe where there is no GPU).
#include "peelcd/gl/context.h"

#include <memory>

namespace peelcd::gl {

class EglContext final : public Context {
 public:
  enum class Platform { any, device, surfaceless };
  explicit EglContext(Platform platform = Platform::any);  // throws GlError
  ~EglContext() override;
  void make_current() override;
  void restore_previous() noexcept override;
  ProcAddress proc_address(const char* name) override;
  std::string backend() const override;  // "egl-device" or "egl-surfaceless"

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::gl
