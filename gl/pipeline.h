#pragma once
// One frame of image-space collision detection over any GL 4.5 core context:
//   AABBs -> overlapping pairs -> per ROI: upload triangles touching the ROI, alternate surface
//   peeling, PCS on the GPU, readback of the PCS list -> expand IDs -> exact narrow phase.
// GL objects (programs, buffers, textures) are created once and reused across ROIs and frames.
#include "core/frame.h"
#include "gl/context.h"

#include <memory>
#include <vector>

namespace peelcd::gl {

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

  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION
  int max_resolution() const;    // GL_MAX_TEXTURE_SIZE

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::gl
