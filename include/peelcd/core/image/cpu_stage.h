#pragma once
// The image stage on the CPU, without GL: a model of what the GL single-pass peeler does, for
// machines without any GL and as a third oracle beside OSMesa and EGL (peelcd detect --backend
// cpu). Per view, each triangle is transformed as the vertex shader does (ROI-local floats,
// the orthographic projection, the viewport), snapped to 1/256 of a texel as llvmpipe's
// rasterizer does, and sampled at texel centres with exact integer edge functions and a
// top-left fill rule; every covered texel centre inside the ROI box gives a fragment (depth
// interpolated on the plane of the snapped triangle, its per-texel slopes). The fragments go into
// the same k-buffer layout as the GL peeler's and are resolved by the same code
// (peelcd/core/image/kbuffer.h): the same layers, PCS test and layer format.
//
// With PeelJob::conservative, each triangle instead covers every texel its projection touches
// (peelcd/core/image/conservative.h, the shaders' arithmetic), with a depth interval per texel.
//
// It models GL's rules, not a particular driver's arithmetic: on the default scene it gives the
// same PCS as OSMesa (tests/gl/test_stages.cpp); elsewhere a texel centre that lies within
// rounding of an edge or of the ROI box may be decided differently.
#include "peelcd/core/image/conservative.h"
#include "peelcd/core/image/image_stage.h"
#include "peelcd/core/image/kbuffer.h"

#include <string>
#include <vector>

namespace peelcd {

class CpuImageStage final : public ImageStage {
 public:
  CpuImageStage() = default;  // one thread: the calling one
  const std::string& backend() const override { return backend_; }
  const std::string& renderer() const override { return renderer_; }
  const std::string& version() const override { return version_; }
  int max_resolution() const override { return 16384; }
  bool runs_on_cpu() const override { return true; }
  StageCost cost() const override;
  void peel(const PeelJob& job, PeelResult& out, Timings& timings) override;

 private:
  struct Fragment {
    std::uint32_t texel;
    KFragment f;
  };
  struct Corner;  // a projected corner (cpu_stage.cpp)
  // The steps of peel(): each object's triangles rasterized into fragments_, then the k-buffer
  // built from them and resolved.
  void raster_object(const PeelJob& job, int slot);
  void raster_point(const Corner (&c)[3], int n, std::uint32_t key, const float box_lo[3], const float box_hi[3]);
  void raster_conservative(const conservative::Triangle& t, int n, std::uint32_t key);
  void resolve(const PeelJob& job, PeelResult& out);
  std::string backend_ = "cpu", renderer_ = "peelcd CPU image stage (k-buffer model)", version_ = "1";
  std::vector<Fragment> fragments_;
  std::vector<std::uint32_t> counts_, ids_[2];
  std::vector<std::uint32_t> selected_[2];  // a rigid object's triangles without a list (job_triangles())
  std::size_t drawn_[2] = {0, 0};
  std::vector<KFragment> slots_, scratch_;
};

}  // namespace peelcd
