#include "peelcd/gl_egl/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <string>
#include <vector>

namespace peelcd::gl {

struct EglContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string platform;
  // The caller's context, current before make_current() (EGL_NO_CONTEXT: none to give back).
  EGLDisplay prev_display = EGL_NO_DISPLAY;
  EGLSurface prev_draw = EGL_NO_SURFACE, prev_read = EGL_NO_SURFACE;
  EGLContext prev_context = EGL_NO_CONTEXT;
};

namespace {

// A GL 4.5 core context on `display`, or EGL_NO_CONTEXT (the display is then terminated).
EGLContext try_display(EGLDisplay display) {
  if (display == EGL_NO_DISPLAY) return EGL_NO_CONTEXT;
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) return EGL_NO_CONTEXT;
  const char* ext = eglQueryString(display, EGL_EXTENSIONS);
  if (!ext || std::string(ext).find("EGL_KHR_surfaceless_context") == std::string::npos ||
      !eglBindAPI(EGL_OPENGL_API)) {
    eglTerminate(display);
    return EGL_NO_CONTEXT;
  }
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  eglChooseConfig(display, config_attribs, &config, 1, &count);  // none is fine: no_config_context
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  EGLContext ctx = eglCreateContext(display, count > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attribs);
  if (ctx == EGL_NO_CONTEXT) eglTerminate(display);
  return ctx;
}

}  // namespace

EglContext::EglContext(Platform platform) : impl_(std::make_unique<Impl>()) {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  const std::string client_ext = client ? client : "";
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display)
    throw GlError("peelcd::gl::EglContext: eglGetPlatformDisplayEXT is missing (is libegl-mesa0 installed?)");

  if (platform != Platform::surfaceless && client_ext.find("EGL_EXT_platform_device") != std::string::npos) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    if (query_devices && query_devices(16, devices, &n)) {
      for (EGLint i = 0; i < n && impl_->context == EGL_NO_CONTEXT; ++i) {
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        impl_->context = try_display(d);
        if (impl_->context != EGL_NO_CONTEXT) {
          impl_->display = d;
          impl_->platform = "egl-device";
        }
      }
    }
  }
  if (impl_->context == EGL_NO_CONTEXT && platform != Platform::device &&
      client_ext.find("EGL_MESA_platform_surfaceless") != std::string::npos) {
    EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    impl_->context = try_display(d);
    if (impl_->context != EGL_NO_CONTEXT) {
      impl_->display = d;
      impl_->platform = "egl-surfaceless";
    }
  }
  if (impl_->context == EGL_NO_CONTEXT)
    throw GlError("peelcd::gl::EglContext: no EGL platform gives an OpenGL 4.5 core context without a surface "
                  "(tried " + std::string(platform == Platform::surfaceless ? "" : "device ") +
                  (platform == Platform::device ? "" : "surfaceless") + ")");
  // Made current once to prove it works, then the caller's context (if any) is current again.
  make_current();
  restore_previous();
}

EglContext::~EglContext() {
  if (bound_context.context == this) bound_context = {};
  if (impl_->context != EGL_NO_CONTEXT) {
    if (eglGetCurrentContext() == impl_->context)
      eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(impl_->display, impl_->context);
    // No eglTerminate: an EGL display is one per platform and device in the whole process, and
    // terminating it would pull it from under every other EglContext on it.
  }
}

void EglContext::make_current() {
  const EGLContext current = eglGetCurrentContext();
  impl_->prev_context = EGL_NO_CONTEXT;
  if (current == impl_->context) {
    if (bound_context.context == this) return;  // already current: nothing to switch or give back
    // Current for EGL, but another platform's context was made current since (one GL dispatch
    // in Mesa): released, then bound again, so that GL calls reach this one.
    eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  } else if (current != EGL_NO_CONTEXT) {
    impl_->prev_context = current;
    impl_->prev_display = eglGetCurrentDisplay();
    impl_->prev_draw = eglGetCurrentSurface(EGL_DRAW);
    impl_->prev_read = eglGetCurrentSurface(EGL_READ);
  }
  if (!eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context)) {
    impl_->prev_context = EGL_NO_CONTEXT;
    throw GlError("peelcd::gl::EglContext: eglMakeCurrent failed");
  }
  bound_context = {this, ContextPlatform::egl};
}

void EglContext::restore_previous() noexcept {
  if (impl_->prev_context == EGL_NO_CONTEXT) return;
  eglMakeCurrent(impl_->prev_display, impl_->prev_draw, impl_->prev_read, impl_->prev_context);
  impl_->prev_context = EGL_NO_CONTEXT;
  bound_context = {};
}

ProcAddress EglContext::proc_address(const char* name) { return reinterpret_cast<ProcAddress>(eglGetProcAddress(name)); }

std::string EglContext::backend() const { return impl_->platform; }

}  // namespace peelcd::gl
