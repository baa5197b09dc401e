#pragma once
// The image stage over any GL 4.5 core context (OSMesa, EGL, or the caller's own): triangles
// of one ROI view uploaded in ROI-local floats, layers peeled by the single-pass k-buffer peeler
// (default) or the multi-pass peeler, PCS found on the GPU (or on the host where GL itself runs on
// the CPU) and read back. GL objects (programs, buffers, textures) are created once and reused
// across views and frames; rigid objects' shapes stay on the GPU while their owner holds them.
//
// GL is called only through function pointers resolved from the context
// (Context::proc_address), so several stages on different platforms live in one process.
// Thread safety: one thread at a time per stage (see peelcd/core/image/detector.h).
#include "peelcd/core/image/image_stage.h"
#include "peelcd/gl/context.h"
#include "peelcd/gl/options.h"

#include <memory>
#include <string>

namespace peelcd::gl {

// A hash of the embedded shader sources (the first 16 hex digits of their SHA-256), recorded with
// goldens and dumps.
std::string shader_sources_hash();

class GlImageStage final : public ImageStage {
 public:
  // Makes `context` current, loads GL through it and compiles the programs, then gives the
  // caller's current context back. The stage shares ownership of the context: it lives as long
  // as the stage. Throws GlError (no GL 4.5 core, a shader that does not compile).
  explicit GlImageStage(std::shared_ptr<Context> context, GlOptions options = {});
  ~GlImageStage() override;
  GlImageStage(const GlImageStage&) = delete;
  GlImageStage& operator=(const GlImageStage&) = delete;

  // The peeler and resolve may change between frames (the worker count is fixed at construction).
  const GlOptions& options() const;
  void set_options(const GlOptions& options);

  const std::string& backend() const override;   // the context's platform
  const std::string& renderer() const override;  // GL_RENDERER
  const std::string& version() const override;   // GL_VERSION
  int max_resolution() const override;           // GL_MAX_TEXTURE_SIZE
  bool runs_on_cpu() const override;             // a software renderer (GL_RENDERER says which)
  // A GPU, or the GPU's resolve asked for (GlOptions::resolve gpu): the production path.
  bool prefers_batches() const override;
  // The router's model: one for GL on the CPU (llvmpipe, lavapipe), one for a GPU
  // (docs/router.md).
  StageCost cost() const override;
  // GL_TIME_ELAPSED queries around every draw, dispatch and large transfer (Timings::gpu_raster,
  // gpu_compute, gpu_transfer).
  void set_pass_timing(bool on) override;
  bool pass_timing() const override;
  void begin_frame() override;
  void end_frame() noexcept override;
  void peel(const PeelJob& job, PeelResult& out, Timings& timings) override;
  // With GlOptions::batch, a frame's conservative views (that capture no layers, or resolve on
  // the host) and the single-pass peeler's point-sampled views that capture nothing are packed
  // into one k-buffer and drawn together: a count and a fill draw for the views (more only when
  // their fragments exceed the largest storage block), the same layers and PCS as peel() on
  // each. Other views, and a view that fills a k-buffer alone, are peeled one by one.
  void peel_batch(const PeelJob* jobs, std::size_t count, PeelResult* outs, Timings& timings) override;

  // Benchmarks: the floor under any image-space method on this context. The job's triangles
  // uploaded (not timed), then drawn once with depth testing and a fragment shader that does
  // nothing; returns the milliseconds of that draw (to glFinish). Call between begin_frame()
  // and end_frame().
  double floor_draw_ms(const PeelJob& job);

  Context& context();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::gl
