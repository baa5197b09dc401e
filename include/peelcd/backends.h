#pragma once
// The image stage of a backend, by the name the command line, scene tools and tests use:
//   "osmesa"  the GL stage on OSMesa (software GL, the deterministic reference)
//   "egl"     the GL stage on EGL without a window (a GPU, or Mesa without one)
//   "cpu"     the CPU image stage (no GL)
// Header-only: compiled where it is used, with the contexts that program links. Linking
// peelcd::gl_egl defines PEELCD_HAVE_EGL, linking peelcd::gl_osmesa PEELCD_HAVE_OSMESA, for their
// users; a backend whose component the program does not link is refused with a message that
// says which (and whether this peelcd was built with it at all). "cpu" needs peelcd::core only.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/version.h"
#if PEELCD_HAVE_EGL || PEELCD_HAVE_OSMESA
#include "peelcd/gl/gl_stage.h"
#endif
#if PEELCD_HAVE_EGL
#include "peelcd/gl_egl/egl_context.h"
#endif
#if PEELCD_HAVE_OSMESA
#include "peelcd/gl_osmesa/osmesa_context.h"
#endif

#include <memory>
#include <stdexcept>
#include <string>

namespace peelcd {

// The default backend: OSMesa where this program has it, else EGL, else the CPU stage.
#if PEELCD_HAVE_OSMESA
inline constexpr const char* kDefaultBackend = "osmesa";
#elif PEELCD_HAVE_EGL
inline constexpr const char* kDefaultBackend = "egl";
#else
inline constexpr const char* kDefaultBackend = "cpu";
#endif

#if PEELCD_HAVE_EGL || PEELCD_HAVE_OSMESA
// A GL context for "osmesa" or "egl" where this program links its component; nullptr for any
// other name (e.g. "cpu").
inline std::shared_ptr<gl::Context> make_gl_context(const std::string& backend) {
#if PEELCD_HAVE_OSMESA
  if (backend == "osmesa") return std::make_shared<gl::OsmesaContext>();
#endif
#if PEELCD_HAVE_EGL
  if (backend == "egl") return std::make_shared<gl::EglContext>();
#endif
  return nullptr;
}
#endif

// The image stage of `backend` (the GL stage with `options`, or the CPU stage). Throws
// std::invalid_argument naming an unknown backend, or one this program cannot start (its
// component not linked, or this peelcd built without it).
#if PEELCD_HAVE_EGL || PEELCD_HAVE_OSMESA
inline std::shared_ptr<ImageStage> make_image_stage(const std::string& backend, const gl::GlOptions& options = {}) {
  if (std::shared_ptr<gl::Context> context = make_gl_context(backend))
    return std::make_shared<gl::GlImageStage>(std::move(context), options);
#else
inline std::shared_ptr<ImageStage> make_image_stage(const std::string& backend) {
#endif
  if (backend == "cpu") return std::make_shared<CpuImageStage>();
#if !PEELCD_HAVE_OSMESA
  if (backend == "osmesa")
    throw std::invalid_argument(
        PEELCD_BUILT_WITH_OSMESA
            ? "peelcd: --backend osmesa: this program does not link peelcd::gl_osmesa (link it, or use egl or cpu)"
            : "peelcd: --backend osmesa: this peelcd was built without OSMesa (PEELCD_WITH_OSMESA=OFF): use egl or cpu");
#endif
#if !PEELCD_HAVE_EGL
  if (backend == "egl")
    throw std::invalid_argument("peelcd: --backend egl: this program does not link peelcd::gl_egl (link it, or use cpu)");
#endif
  throw std::invalid_argument("peelcd: --backend: unknown backend \"" + backend + "\" (expected osmesa, egl or cpu)");
}

}  // namespace peelcd
