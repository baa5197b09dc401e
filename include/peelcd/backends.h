#pragma once
// The image stage of a backend, by the name the command line, scene tools and tests use:
//   "osmesa"  the GL stage on OSMesa (software GL, the deterministic reference)
//   "egl"     the GL stage on EGL without a window (a GPU, or Mesa without one)
//   "cpu"     the CPU image stage (no GL)
// Header-only: compiled where it is used, with the contexts that program links. Linking
// peelcd::gl_osmesa defines PEELCD_HAVE_OSMESA for its users; without it "osmesa" is refused
// with a message that says so. Needs peelcd::gl_egl (and peelcd::gl_osmesa for "osmesa").
#include "peelcd/core/cpu_stage.h"
#include "peelcd/gl/gl_stage.h"
#include "peelcd/gl_egl/egl_context.h"
#if PEELCD_HAVE_OSMESA
#include "peelcd/gl_osmesa/osmesa_context.h"
#endif

#include <memory>
#include <stdexcept>
#include <string>

namespace peelcd {

// The default backend: OSMesa where this program has it, else EGL.
#if PEELCD_HAVE_OSMESA
inline constexpr const char* kDefaultBackend = "osmesa";
#else
inline constexpr const char* kDefaultBackend = "egl";
#endif

// A GL context for "osmesa" or "egl"; nullptr for any other name (e.g. "cpu").
inline std::shared_ptr<gl::Context> make_gl_context(const std::string& backend) {
#if PEELCD_HAVE_OSMESA
  if (backend == "osmesa") return std::make_shared<gl::OsmesaContext>();
#endif
  if (backend == "egl") return std::make_shared<gl::EglContext>();
  return nullptr;
}

// The image stage of `backend` (the GL stage with `options`, or the CPU stage). Throws
// std::invalid_argument naming an unknown backend, or one this program was built without.
inline std::shared_ptr<ImageStage> make_image_stage(const std::string& backend, const gl::GlOptions& options = {}) {
  if (std::shared_ptr<gl::Context> context = make_gl_context(backend))
    return std::make_shared<gl::GlImageStage>(std::move(context), options);
  if (backend == "cpu") return std::make_shared<CpuImageStage>();
#if !PEELCD_HAVE_OSMESA
  if (backend == "osmesa")
    throw std::invalid_argument(
        "peelcd: --backend osmesa: this peelcd was built without OSMesa (PEELCD_WITH_OSMESA=OFF): use egl or cpu");
#endif
  throw std::invalid_argument("peelcd: --backend: unknown backend \"" + backend + "\" (expected osmesa, egl or cpu)");
}

}  // namespace peelcd
