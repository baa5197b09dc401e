#pragma once
// The image stage: what a backend must do for the detector (peelcd/core/image/detector.h). Given one
// ROI view of two objects and the triangles of each that touch it, peel the layers and return
// the PCS (and the layers themselves when asked to capture them). Everything else of a frame
// (broad phase, culling, tiles, views, ID expansion, the exact narrow phase) is the detector's.
//
// Implementations: gl::GlImageStage (peelcd/gl/gl_stage.h: OSMesa, EGL; single-pass and
// multi-pass peelers) and CpuImageStage (peelcd/core/image/cpu_stage.h: no GL at all).
#include "peelcd/core/frame.h"
#include "peelcd/core/image/view.h"

#include <cstdint>
#include <string>
#include <vector>

namespace peelcd {

// One ROI view to peel. Object 0 is the pair's A, object 1 its B.
struct PeelJob {
  const Object* objects[2] = {nullptr, nullptr};
  // The triangles of each object to draw, ascending: those whose box touches view.box (after
  // contact culling). Never empty when a stage is called. Null for a rigid object or a moving
  // mesh: every triangle of its shape whose box, through its pose (or of its moving mesh), touches
  // the view (job_triangles()); the GL stage's batch selects those on the GPU, the other paths on
  // the host.
  const std::vector<std::uint32_t>* triangles[2] = {nullptr, nullptr};
  RoiView view;                    // the padded ROI view (box, frame, resolution)
  std::size_t pair_index = 0;      // the object pair (FrameResult::pairs) and fused view (0..2)
  int view_index = 0;              // this job belongs to
  IdMode ids = IdMode::ring;
  PeelMode peel = PeelMode::full;
  double epsilon = 0.0;            // PCS depth threshold, world units
  double slope = 0.0;              // slope factor of the PCS test (DetectOptions::slope)
  int first = 1;                   // the object alternate peeling starts with (0 = A, 1 = B)
  bool capture = false;            // also fill PeelResult::captured with every layer
  // Conservative coverage and depth intervals (DetectOptions::conservative): a fragment holds
  // (lower depth bits, object << 31 | ID + 1, upper depth bits, 0); the PCS are all overlapping
  // couples of different objects in a texel; `peel`, `epsilon` and `slope` do not apply.
  bool conservative = false;
  // Conservative mode, proximity (DetectOptions::margin): every triangle is grown by `grow`
  // (world units, half the margin) on every side, so that two triangles within the margin of
  // each other overlap in a texel (at their closest points' midpoint) and make a PCS.
  double grow = 0.0;
};

// What a stage returns for one job.
struct PeelResult {
  std::vector<IdPair> pcs;         // (ID of A, ID of B), any order, repeats allowed
  int layers = 0;                  // non-empty logical layers
  int peel_passes = 0;             // peel passes drawn (multi-pass: layers + 1; single pass: 1)
  float epsilon_window = 0.0f;     // the PCS threshold in window depth, as the test applied it
  float slope = 0.0f;              // the slope factor, as the test applied it
  // Counters of the work done (FrameResult's).
  std::size_t gl_passes = 0, pcs_readbacks = 0, triangles_uploaded = 0, triangles_indexed = 0, shape_uploads = 0;
  // With PeelJob::capture: every logical layer in peel order, N*N texels of 4 words each
  // (depth bits, object << 31 | ID + 1 (0 = empty), dz/dx bits, dz/dy bits), rows bottom to top;
  // in conservative mode (lower depth bits, object << 31 | ID + 1, upper depth bits, 0), every
  // fragment of a texel a layer, in (lower depth, object, draw order) order.
  std::vector<std::vector<std::uint32_t>> captured;
  // The stage could not resolve this view conservatively (a texel deeper than the largest
  // k-buffer it can hold): the detector tests every couple of the view's triangles whose boxes
  // overlap instead (`pcs` is then empty). Never set outside conservative mode.
  bool exhaustive = false;

  void clear() {
    exhaustive = false;
    pcs.clear();
    captured.clear();
    layers = peel_passes = 0;
    epsilon_window = slope = 0.0f;
    gl_passes = pcs_readbacks = triangles_uploaded = triangles_indexed = shape_uploads = 0;
  }
};

// What one ROI view costs this stage, for the stage router (Stage::automatic): predicted
// milliseconds = view_ms + triangle_us / 1e3 * triangles drawn + texel_ns / 1e6 * texels of the
// tile, per view. Calibrated per backend with `peelcd calibrate` (docs/performance.md).
struct StageCost {
  double view_ms = 0.0;
  double triangle_us = 0.0;
  double texel_ns = 0.0;
  // The frame API's scan before either path: culling reads every triangle of both objects
  // (us per triangle). The same for both paths (it does not change a route); part of the
  // predictions so that they say what a pair costs (exact_path_cost() holds it).
  double scan_us = 0.0;
  double predict_ms(double triangles, double texels) const {
    return view_ms + triangle_us * 1e-3 * triangles + texel_ns * 1e-6 * texels;
  }
};

// What a stage did on the GL side (FrameResult::gl_counters copies them for a frame): the counts
// that say whether a frame's GL work follows its ROIs or is constant, measurable on llvmpipe.
struct StageCounters {
  std::size_t draws = 0;           // draw calls
  std::size_t dispatches = 0;      // compute dispatches
  std::size_t readbacks = 0;       // reads of GL memory by the host (maps, gets): each waits for the GPU
  std::size_t bytes_uploaded = 0;  // bytes the host wrote into GL buffers (buffer data and sub-data)
  // Of those, mesh data: corners, corner indices, draw entries (per triangle); the rest is per
  // view or per texel (matrices, selection jobs, commands, offsets, headers).
  std::size_t geometry_bytes = 0;
  std::size_t bytes_read = 0;      // bytes the host read back
  // The GPU resolve's deep texels (more fragments than PEELCD_GPU_RESOLVE_DEPTH,
  // peelcd/core/image/pcs_test.inc): split over invocations (batched conservative views), or their
  // views resolved on the host instead (every other GPU resolve; never silent).
  std::size_t deep_texels = 0;
  std::size_t views_host_resolved = 0;
  // Couples of fragments (overlapping in depth, of two objects, in one texel) whose triangles the
  // GPU resolve's certified filter proved apart and did not write (GlOptions::gpu_filter).
  std::size_t couples_apart = 0;
};

// What the stage counted in the frame (GL calls and bytes), into the frame's result.
inline void copy_stage_counters(const StageCounters& c, FrameResult& out) {
  out.gl_draws = c.draws;
  out.gl_dispatches = c.dispatches;
  out.gl_readbacks = c.readbacks;
  out.bytes_uploaded = c.bytes_uploaded;
  out.bytes_read = c.bytes_read;
  out.geometry_bytes = c.geometry_bytes;
  out.gl_deep_texels = c.deep_texels;
  out.gl_couples_apart = c.couples_apart;
  out.views_host_resolved = c.views_host_resolved;
}

// One peeled view's work counters, added to the frame's.
inline void add_view_counters(const PeelResult& one, FrameResult& out) {
  out.gl_passes += one.gl_passes;
  out.pcs_readbacks += one.pcs_readbacks;
  out.triangles_uploaded += one.triangles_uploaded;
  out.triangles_indexed += one.triangles_indexed;
  out.shape_uploads += one.shape_uploads;
}

// Job's triangle list of object `slot`: PeelJob::triangles[slot], or, where that is null, the
// triangles of its shape whose box through its pose (a rigid object; in double), or of its moving
// mesh (world space), touches the view's box grown by job.grow, written into `scratch`
// (ascending). Throws std::invalid_argument for a null list of an object with neither.
const std::vector<std::uint32_t>& job_triangles(const PeelJob& job, int slot, std::vector<std::uint32_t>& scratch);

// The stage router's two models and where they came from: a file written by `peelcd calibrate
// --write-costs` (peelcd/io/costs.h reads it; fitted on one backend and renderer), or, with
// `source` empty, the stage's built-in models (ImageStage::cost(), exact_path_cost()).
struct CostModels {
  StageCost image, exact;
  std::string source;             // the file; empty: built in
  std::string backend, renderer;  // what the file's models were fitted on
  // The GL stage's conservative coverage that calibrate timed faster on that device ("raster",
  // "compute"; empty: not timed): GlOptions::coverage auto follows it.
  std::string coverage;
};

// The exact CPU path's built-in cost model (view_ms + triangle_us per kept triangle, scan_us per
// scanned triangle), fitted by `peelcd calibrate` on the machine docs/performance.md names.
StageCost exact_path_cost();

class ImageStage {
 public:
  virtual ~ImageStage() = default;
  // The models the stage router uses for this stage: set_cost_models()' (a calibration file),
  // else the built-in ones. The Detector and the World read them every frame.
  void set_cost_models(const CostModels& models) { models_ = models; }
  void clear_cost_models() { models_ = CostModels{}; }
  StageCost router_image_cost() const { return models_.source.empty() ? cost() : models_.image; }
  StageCost router_exact_cost() const { return models_.source.empty() ? exact_path_cost() : models_.exact; }
  const CostModels& cost_models() const { return models_; }  // source empty: built in
  // Counted by the stage as it works; the Detector zeroes them when a frame begins.
  StageCounters counters;
  virtual const std::string& backend() const = 0;   // "osmesa", "egl-device", "egl-surfaceless", "cpu"
  virtual const std::string& renderer() const = 0;  // GL_RENDERER, or a description of the CPU model
  virtual const std::string& version() const = 0;   // GL_VERSION, or the CPU model's version
  virtual int max_resolution() const = 0;    // the largest N of an N x N view
  // The stage's work runs on the host's cores (the CPU stage; GL on llvmpipe, softpipe, swrast):
  // no GPU to overlap with, so batching and GPU-side work do not pay (the World peels its image
  // pairs one at a time there; the GL stage resolves on the host).
  virtual bool runs_on_cpu() const { return false; }
  // The World sends its image-routed pairs to peel_batch() together (World::batch_image_pairs()
  // unset): on a GPU, and where a stage on the CPU was asked to run a GPU's production path.
  virtual bool prefers_batches() const { return !runs_on_cpu(); }
  // The router's model of this stage. The default (all zero) predicts it free: a stage that
  // does not model its cost always peels (as before the router existed).
  virtual StageCost cost() const { return StageCost{}; }
  // GPU timer queries around each pass (Timings::gpu_raster, gpu_compute, gpu_transfer, and
  // gpu_timed set), collected as each peel() or peel_batch() returns. Off by default: a stage
  // without GPU passes (the CPU stage) ignores it.
  virtual void set_pass_timing(bool on) { (void)on; }
  virtual bool pass_timing() const { return false; }
  // Bracket the jobs of one frame (a GL stage makes its context current in begin_frame() and
  // gives the caller's current context back in end_frame()).
  virtual void begin_frame() {}
  virtual void end_frame() noexcept {}
  // Peels `job` into `out` (cleared first). Adds its time to `timings` (upload, gpu, readback,
  // gl_wait; the GPU passes' with pass timing on).
  virtual void peel(const PeelJob& job, PeelResult& out, Timings& timings) = 0;
  // Peels `count` jobs (every ROI view of a frame) into outs[0..count): the same results as
  // peel() on each, in any order of work. A stage may draw them together (the GL stage packs
  // conservative views into one k-buffer: one draw for all of them); the counters of the shared
  // work (gl_passes) are then reported on the first job of the batch. The default peels each.
  virtual void peel_batch(const PeelJob* jobs, std::size_t count, PeelResult* outs, Timings& timings) {
    for (std::size_t i = 0; i < count; ++i) peel(jobs[i], outs[i], timings);
  }

 private:
  CostModels models_;
};

// Ends the stage's frame (ImageStage::end_frame(): the caller's context given back) when the
// scope ends, also on an exception; nothing while `stage` is null (no frame begun).
struct StageFrameScope {
  ImageStage* stage = nullptr;
  ~StageFrameScope() {
    if (stage) stage->end_frame();
  }
};

}  // namespace peelcd
