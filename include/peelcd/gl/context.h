#pragma once
// The only thing the GL image stage knows about a GL platform: make a GL 4.5 core context
// current (remembering the caller's), give the caller's back, and resolve function pointers from
// it. Platforms (peelcd/gl_osmesa, peelcd/gl_egl, or a caller's own) stay this small.
//
// A context supplied by the caller: derive from Context, make your context current in
// make_current() (remembering what was current), restore it in restore_previous(), and resolve
// names with your platform's GetProcAddress. The stage calls make_current() at the start of each
// frame and restore_previous() at its end, on the thread that runs the frame.
#include <stdexcept>
#include <string>

namespace peelcd::gl {

using ProcAddress = void (*)();

class Context {
 public:
  virtual ~Context() = default;
  // Makes this context current on the calling thread; remembers the context of the same
  // platform that was current before, if another one was.
  virtual void make_current() = 0;
  // Makes the context remembered by the last make_current() current again. Leaves this one
  // current when nothing else was (nothing to give back). Never throws.
  virtual void restore_previous() noexcept {}
  virtual ProcAddress proc_address(const char* name) = 0;
  virtual std::string backend() const = 0;  // "osmesa", "egl-device", "egl-surfaceless", ...
};

// The peelcd context this thread last made current, of any platform (null after one gave the
// caller's context back). Mesa's OSMesa and its EGL drivers share one GL dispatch (libglapi):
// after another platform's context was made current, a context its own platform still reports
// current is not the one GL calls reach, and OSMesaGetCurrentContext() reads the other
// platform's context as if it were OSMesa's. Each make_current() checks this record first (the
// pointer is compared, never followed: the context may be gone; a context clears it when it goes).
enum class ContextPlatform { none, osmesa, egl };
struct BoundContext {
  const Context* context = nullptr;
  ContextPlatform platform = ContextPlatform::none;
};
inline thread_local BoundContext bound_context;

// A context could not be created or made current, or a GL call failed.
struct GlError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace peelcd::gl
