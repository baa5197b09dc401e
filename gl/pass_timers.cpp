// The GL stage's clocks: GPU timer queries around its passes (ImageStage::set_pass_timing) and the
// host's time blocked in GL reads (Timings::gl_wait), handed to the caller's Timings as each call
// of the stage returns.
#include "stage_impl.h"

namespace peelcd::gl {

void PassTimers::begin(GpuPass kind) {
  if (!on) return;
  if (used_ == pool_.size()) {
    pool_.resize(pool_.empty() ? 64 : pool_.size() * 2, 0);
    gl_->CreateQueries(GL_TIME_ELAPSED, GLsizei(pool_.size() - used_), pool_.data() + used_);
    kinds_.resize(pool_.size());
  }
  if (used_ == 0) first_ = Clock::now();
  kinds_[used_] = kind;
  gl_->BeginQuery(GL_TIME_ELAPSED, pool_[used_]);
  open_ = true;
}

void PassTimers::end() {
  if (!open_) return;
  gl_->EndQuery(GL_TIME_ELAPSED);
  open_ = false;
  ++used_;
}

void PassTimers::collect(Timings& t) {
  if (!on) return;
  t.gpu_timed = true;
  // Every query ended before the stage's last read back, which waited for the GPU: the results
  // are there (GL_QUERY_RESULT waits only where a driver has not published them yet). A pass
  // cannot take longer than the host's time since the first of them began.
  const double wall_ms = used_ ? ms_since(first_) : 0.0;
  for (std::size_t i = 0; i < used_; ++i) {
    GLuint64 ns = 0;
    gl_->GetQueryObjectui64v(pool_[i], GL_QUERY_RESULT, &ns);
    const double ms = double(ns) * 1e-6;
    if (ms > wall_ms) {
      ++t.gpu_passes_untimed;
      continue;
    }
    switch (kinds_[i]) {
      case GpuPass::raster: t.gpu_raster += ms; break;
      case GpuPass::transfer: t.gpu_transfer += ms; break;
      case GpuPass::select: t.gpu_select += ms, t.gpu_compute += ms; break;
      case GpuPass::cover: t.gpu_cover += ms, t.gpu_compute += ms; break;
      case GpuPass::compute: t.gpu_compute += ms; break;
    }
  }
  used_ = 0;
}

void PassTimers::release() {
  if (!pool_.empty()) gl_->DeleteQueries(GLsizei(pool_.size()), pool_.data());
  pool_.clear();
  kinds_.clear();
  used_ = 0;
}

// The stage's clocks into the caller's timings: the GL wait and, with pass timing, the passes.
void GlImageStage::Impl::hand_clocks(Timings& t) {
  t.gl_wait += wait_ms;
  wait_ms = 0.0;
  timers.collect(t);
}

void GlImageStage::set_pass_timing(bool on) { impl_->timers.on = on; }
bool GlImageStage::pass_timing() const { return impl_->timers.on; }

}  // namespace peelcd::gl
