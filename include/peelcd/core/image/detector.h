#pragma once
// The frame of image-space collision detection, independent of the backend that peels:
//   world AABBs -> overlapping pairs (ROIs) -> per ROI: contact culling, tile, fused views ->
//   per view: the triangles touching it, the object peeled first -> ImageStage::peel -> PCS ->
//   PCS of all views united -> IDs expanded into candidate triangle pairs -> exact narrow phase.
//
// Thread safety: a Detector and its stage are used by one thread at a time (one detector per
// thread; stages are not shared between detectors that run concurrently). Distinct detectors
// with distinct stages may run on distinct threads.
#include "peelcd/core/frame.h"
#include "peelcd/core/image/image_stage.h"
#include "peelcd/core/image/planner.h"

#include <functional>
#include <memory>
#include <vector>

namespace peelcd {

// Every logical layer of one ROI view, as the stage produced it: the oracle's raw material
// (layer dumps, goldens). Texels as in PeelResult::captured.
struct CapturedView {
  std::size_t pair = 0;        // index into FrameResult::pairs
  int view = 0;                // index of the fused view (fused_view_frames)
  RoiView roi;                 // the padded ROI view that was peeled
  bool a_first = false;        // object A was peeled first
  float epsilon_window = 0;    // the PCS threshold in window depth, as the stage applied it
  float slope = 0;             // the slope factor, as the stage applied it
  std::vector<std::vector<std::uint32_t>> layers;  // logical layers in peel order, N*N*4 words each
  std::vector<IdPair> pcs;     // this view's PCS (ID of A, ID of B), sorted, distinct
};

// Checks what a frame needs of its objects: finite coordinates, triangle indices within the
// vertex list, IDs that fit the layers' 31 bits, a rigid object's shape with as many triangles
// as its world mesh. Throws std::invalid_argument naming the object (index and name) and the
// problem. Empty meshes are allowed (they overlap nothing).
// With `float_range` (any frame that may use the image stage, which works in float), a
// coordinate beyond float's range (|x| > 3.4e38) is refused too; the exact CPU path alone
// (Stage::exact) takes every finite double. A rigid pose must be finite and invertible.
void validate_objects(const std::vector<Object>& objects, bool float_range = true);
void validate_objects(const std::vector<const Object*>& objects, bool float_range = true);
void validate_object(const Object& object, std::size_t index, bool float_range = true);
// The same, the message naming the object by `label` (e.g. "object 'b'").
void validate_object(const Object& object, const std::string& label, bool float_range = true);

// The largest finite float: the image stage's coordinate range.
constexpr double kFloatMax = 3.4028234663852886e38;
// Empty if `p` is finite (and, with `float_range`, within float's range), else the problem in
// words ("has a NaN or infinite coordinate", "(x, y, z) is outside the float range ...").
std::string coordinate_problem(const Vec3& p, bool float_range);
// Empty if `pose` is usable (finite, its linear part invertible), else the problem in words.
std::string pose_problem(const Eigen::Affine3d& pose);

// Checks the options (ranges, finiteness) against a stage whose largest view is
// `max_resolution`. Throws std::invalid_argument naming the option.
void validate_options(const DetectOptions& options, int max_resolution);

// The triangles of `mesh` (all, or those listed in `only`, ascending) whose box touches
// `view.box` (grown by `grow` on every side), ascending, into `out`. Returns the smallest depth
// along the view direction of their corners, clamped to [-half_depth, half_depth] (half_depth
// when there is none).
double triangles_in_view(const Mesh& mesh, const RoiView& view, const std::vector<std::uint32_t>* only,
                         std::vector<std::uint32_t>& out, double grow = 0.0);

// Triangle t's box touches `box` (closed): the test of triangles_touching() and culling's ROI.
bool triangle_touches(const Mesh& mesh, std::uint32_t t, const Aabb& box);

// The triangles of `mesh` whose boxes touch `box` (closed), ascending, into `out`: the crop to
// an overlap box (the router's triangles with Cull::box; the benchmark's CGAL peer).
void triangles_touching(const Mesh& mesh, const Aabb& box, std::vector<std::uint32_t>& out);

class Detector {
 public:
  // The detector shares ownership of its stage (a GL stage owns its context in turn).
  explicit Detector(std::shared_ptr<ImageStage> stage);
  ~Detector();
  Detector(const Detector&) = delete;
  Detector& operator=(const Detector&) = delete;

  // One frame. Objects are world-space meshes; they are validated (validate_objects) and the
  // options checked (validate_options): std::invalid_argument on bad input. A stage failure
  // (e.g. gl::GlError) propagates.
  FrameResult detect(const std::vector<Object>& objects, const DetectOptions& options);
  // The same into `out`, reusing its storage: with the same number of overlapping pairs frame
  // after frame, the detector allocates nothing (the stage may, inside its driver).
  void detect(const std::vector<Object>& objects, const DetectOptions& options, FrameResult& out);
  // The same over objects held elsewhere (no copy of any mesh; none may be null).
  void detect(const std::vector<const Object*>& objects, const DetectOptions& options, FrameResult& out);

  // While `pairs` is set (sorted (a, b) object pairs, a < b), detect() takes only those of the
  // pairs whose boxes overlap, not every one: a caller that gathers many pairs' objects into one
  // frame (the World's image-routed pairs: one batch for all of them) asks for its own pairs
  // alone. nullptr (the default): every overlapping pair.
  void only_pairs(const std::vector<std::pair<std::size_t, std::size_t>>* pairs);

  // While `sink` is set, detect() appends one CapturedView per ROI view it peels (the stage
  // reads every layer back). nullptr (the default) turns capture off.
  void capture_layers(std::vector<CapturedView>* sink);

  // Calls `fn` with every ROI view detect() would peel for `objects` under `options` (the same
  // culling, tiles, triangles and first object), without peeling: the benchmarks' floor draws
  // exactly what a frame draws. The job's epsilon is the one detect() would use.
  void for_each_view(const std::vector<Object>& objects, const DetectOptions& options,
                     const std::function<void(const PeelJob&)>& fn);

  ImageStage& stage() { return *stage_; }
  const std::shared_ptr<ImageStage>& stage_ptr() const { return stage_; }

 private:
  struct Impl;
  std::shared_ptr<ImageStage> stage_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd
