#pragma once
// One frame of image-space collision detection over any GL 4.5 core context:
//   AABBs -> overlapping pairs -> per ROI: upload triangles touching the ROI, alternate surface
//   peeling, PCS on the GPU, readback of the PCS list -> expand IDs -> exact narrow phase.
// GL objects (programs, buffers, textures) are created once and reused across ROIs and frames.
#include "core/frame.h"
#include "core/id_map.h"
#include "core/view.h"
#include "gl/context.h"

#include <memory>
#include <vector>

namespace peelcd::gl {

// Every logical layer of one ROI view, as read back from the GPU: the oracle's raw material
// (layer dumps, goldens). A texel is 4 words, RGBA32UI as in shaders/peel.frag: depth bits,
// object << 31 | ID + 1 (0 = empty), dz/dx bits, dz/dy bits. Rows run bottom to top (GL order).
struct CapturedView {
  std::size_t pair = 0;        // index into FrameResult::pairs
  int view = 0;                // index of the fused view (core/frame.h fused_view_frames)
  RoiView roi;                 // the padded ROI view that was peeled
  bool a_first = false;        // object A was peeled first
  float epsilon_window = 0;    // the PCS threshold in window depth, as the shader got it
  float slope = 0;             // the slope factor, as the shader got it
  std::vector<std::vector<std::uint32_t>> layers;  // logical layers in peel order, N*N*4 words each
  std::vector<IdPair> pcs;     // this view's PCS (ID of A, ID of B), sorted, distinct
};

// FNV-1a hash of the embedded shader sources (hex), recorded with goldens.
std::string shader_sources_hash();

class Pipeline {
 public:
  // Makes `context` current, loads GL through it and compiles the programs. Throws GlError.
  explicit Pipeline(Context& context);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Objects are world-space meshes (validated by the caller). Throws std::invalid_argument on
  // bad options (e.g. a resolution above max_resolution()), GlError on a GL failure.
  FrameResult detect(const std::vector<Object>& objects, const DetectOptions& options);
  // The same into `out`, reusing its storage: with the same number of overlapping pairs frame
  // after frame, this allocates nothing (beyond what the GL driver does inside its calls).
  void detect(const std::vector<Object>& objects, const DetectOptions& options, FrameResult& out);

  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION
  int max_resolution() const;    // GL_MAX_TEXTURE_SIZE

  // Benchmarks: the floor under any image-space method on this context. Per ROI view (as
  // detect() would peel them) the same triangles, already uploaded, drawn once with depth
  // testing and a fragment shader that does nothing; returns the milliseconds of those draws
  // (to glFinish), excluding culling, gathering and upload. With options.cull == Cull::box, every
  // triangle touching the overlap box (the paper's ROI: the floor of the benchmark); with
  // Cull::contact, the triangles culling keeps, in the shrunk box. With `per_view`, also the
  // milliseconds of each view (summed over the ROIs; the first k of them are the floor of k views).
  double floor_ms(const std::vector<Object>& objects, const DetectOptions& options,
                  std::vector<double>* per_view = nullptr);

  // Debugging and goldens: while `sink` is set, detect() appends one CapturedView per ROI view
  // it peels (reading every layer back, which costs a full texture transfer per layer).
  // nullptr (the default) turns capture off.
  void capture_layers(std::vector<CapturedView>* sink);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::gl
