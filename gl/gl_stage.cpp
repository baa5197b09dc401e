// The public face of the GL image stage: construction, frame bracketing (the caller's context
// given back), one job's geometry and peel, and the benchmarks' floor draw.
#include "stage_impl.h"

namespace peelcd::gl {

std::string shader_sources_hash() { return shaders::shader_sources_hash; }

GlImageStage::GlImageStage(std::shared_ptr<Context> context, GlOptions options) {
  if (!context) throw GlError("peelcd::gl::GlImageStage: no context");
  context->make_current();
  try {
    impl_ = std::make_unique<Impl>(context, options);
    impl_->counters = &counters;
    impl_->models = &cost_models();
  } catch (...) {
    context->restore_previous();
    throw;
  }
  context->restore_previous();
}

GlImageStage::~GlImageStage() = default;

const GlOptions& GlImageStage::options() const { return impl_->options; }
void GlImageStage::set_options(const GlOptions& options) {
  const unsigned workers = impl_->options.workers;  // fixed: the pool's threads exist already
  impl_->options = options;
  impl_->options.workers = workers;
}
const std::string& GlImageStage::backend() const { return impl_->backend; }
const std::string& GlImageStage::renderer() const { return impl_->renderer; }
const std::string& GlImageStage::version() const { return impl_->version; }
int GlImageStage::max_resolution() const { return impl_->max_texture; }
bool GlImageStage::runs_on_cpu() const { return impl_->software_renderer; }
bool GlImageStage::prefers_batches() const {
  return !impl_->software_renderer || impl_->options.resolve == Resolve::gpu;
}

StageCost GlImageStage::cost() const {
  // llvmpipe: fitted by `peelcd calibrate --backend osmesa` on 2 cores (2026-11-25, after the
  // batched views got their count pass: the texel term fell from 19.5 to about 1 ns; triangles
  // counted after one culling round, as the router sees them). A GPU: fitted by
  // `peelcd calibrate --backend egl` on an NVIDIA H200 (2026-11-25, docs/backends.md).
  // See docs/performance.md, "The stage router".
  if (impl_->software_renderer) return StageCost{0.195, 1.44, 0.98};
  return StageCost{0.16, 0.72, 0.0};
}
Context& GlImageStage::context() { return *impl_->context; }

void GlImageStage::begin_frame() {
  impl_->context->make_current();
  impl_->drop_expired_shapes();
}

void GlImageStage::end_frame() noexcept { impl_->context->restore_previous(); }

double GlImageStage::floor_draw_ms(const PeelJob& job) {
  Impl& s = *impl_;
  for (int slot = 0; slot < 2; ++slot)
    s.prepare(*job.objects[slot], job.view, job_triangles(job, slot, s.selected[slot]), job.ids, slot);
  s.upload(0);
  s.upload(1);
  const int tile = job.view.resolution;
  s.ensure_layers(tile);
  s.gl.Finish();
  const auto t0 = Clock::now();
  s.gl.UseProgram(s.floor_draw.id);
  s.set_view_uniforms(s.floor_draw.clip, s.floor_draw.lo, s.floor_draw.hi, job.view);
  s.gl.BindFramebuffer(GL_FRAMEBUFFER, s.fbo[0]);
  s.gl.Viewport(0, 0, tile, tile);
  s.gl.Enable(GL_DEPTH_TEST);
  s.gl.DepthFunc(GL_LESS);
  for (int i = 0; i < 6; ++i) s.gl.Enable(GL_CLIP_DISTANCE0 + i);
  const GLfloat far_depth = 1.0f;
  s.gl.ClearBufferfv(GL_DEPTH, 0, &far_depth);
  s.gl.BindVertexArray(s.vao);
  for (int slot = 0; slot < 2; ++slot) s.draw(slot, s.floor_draw.model);
  s.gl.Finish();
  const double ms = ms_since(t0);
  Timings untimed;  // the floor is no frame's: its timer queries (with pass timing) dropped
  s.timers.collect(untimed);
  s.gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  s.check("the floor draw");
  return ms;
}

// The stage's one-view entry: the view's geometry uploaded, then peeled by the configured peeler.
void GlImageStage::peel(const PeelJob& job, PeelResult& out, Timings& timings) {
  impl_->peel_one(job, out, timings);
  impl_->hand_clocks(timings);
}


void GlImageStage::Impl::peel_one(const PeelJob& job, PeelResult& out, Timings& timings) {
  out.clear();
  const auto t0 = Clock::now();
  shape_uploads = 0;
  for (int slot = 0; slot < 2; ++slot)
    prepare(*job.objects[slot], job.view, job_triangles(job, slot, selected[slot]), job.ids, slot);
  upload(0);
  upload(1);
  timings.upload += ms_since(t0);
  for (int slot = 0; slot < 2; ++slot)
    (slot_shape[slot] ? out.triangles_indexed : out.triangles_uploaded) += corners(slot) / 3;
  out.shape_uploads = shape_uploads;
  if (job.conservative) {  // intervals need every fragment at once: the k-buffer
    while (!peel_conservative(job, out, timings)) {
    }
  } else if (options.peeler == Peeler::abuffer) {
    while (!peel_single_pass(job, out, timings)) {
    }
  } else {
    while (!peel_multipass(job, out, timings)) {
    }
  }
}

}  // namespace peelcd::gl
