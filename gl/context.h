#pragma once
// The only thing the pipeline knows about a GL platform: make a GL 4.5 core context current and
// resolve function pointers from it. Platforms (gl_osmesa/, later gl_egl/) stay this small.
#include <stdexcept>
#include <string>

namespace peelcd::gl {

using ProcAddress = void (*)();

class Context {
 public:
  virtual ~Context() = default;
  virtual void make_current() = 0;
  virtual ProcAddress proc_address(const char* name) = 0;
  virtual std::string backend() const = 0;  // "osmesa", "egl", ...
};

// A context could not be created or made current, or a GL call failed.
struct GlError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace peelcd::gl
