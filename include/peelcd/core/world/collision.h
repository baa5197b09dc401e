#pragma once
// The collision API in the shape FCL and Coal users know: geometry given once, a pose per query,
// a request and a result.
//
//   peelcd::CollisionGeometry  a triangle mesh (shared, validated once); rigid use keeps it on
//                              the GPU across frames
//   peelcd::CollisionObject    a geometry with a pose (rigid), or a mesh whose vertices the
//                              caller updates in place every frame (deforming)
//   peelcd::collide(...)       one pair: the colliding triangle pairs and their segments
//   peelcd::CollisionWorld     many objects, every overlapping pair in one frame
//
// Everything runs through a Detector (peelcd/core/image/detector.h) on some image stage: a GL stage
// (peelcd/gl/gl_stage.h) or the CPU stage (peelcd/core/image/cpu_stage.h). Errors: bad geometry or
// poses throw std::invalid_argument naming the object and the problem; a stage failure throws
// the stage's error (gl::GlError). Thread safety: as the detector's (one thread at a time per
// detector; geometries may be shared read-only between threads).
#include "peelcd/core/image/detector.h"

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace peelcd {

class World;

// An immutable triangle mesh in its own (local) frame. Validated on construction.
class CollisionGeometry {
 public:
  // Throws std::invalid_argument (naming `name`) on an out-of-range index or a NaN / infinite
  // coordinate.
  CollisionGeometry(Mesh mesh, std::string name = {});
  const Mesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const Mesh>& shared_mesh() const { return mesh_; }
  const std::string& name() const { return name_; }

 private:
  std::shared_ptr<const Mesh> mesh_;
  std::string name_;
};

// One object of a frame. Rigid: a geometry and a pose (rotation, translation, optionally a
// uniform scale); the image stage keeps the geometry and uploads only indices. Deforming: a mesh
// owned by the object whose vertices the caller changes in place between frames
// (deforming_vertices()); its triangles may change too (fracture) through deforming_mesh().
class CollisionObject {
 public:
  CollisionObject(std::shared_ptr<const CollisionGeometry> geometry, const Eigen::Affine3d& pose,
                  std::string name = {});
  static CollisionObject deforming(Mesh mesh, std::string name = {});

  bool rigid() const { return geometry_ != nullptr; }
  // Rigid objects: the geometry (nullptr for a deforming object).
  const std::shared_ptr<const CollisionGeometry>& geometry() const { return geometry_; }
  const std::string& name() const { return object_.name; }
  // Rigid objects: the pose, world = pose * local. Throws std::invalid_argument on a pose with a
  // NaN or infinite entry.
  void set_pose(const Eigen::Affine3d& pose);
  const Eigen::Affine3d& pose() const;
  // Deforming objects: the mesh to change in place (std::logic_error on a rigid object).
  std::vector<Vec3>& deforming_vertices();
  Mesh& deforming_mesh();

  // The world-space object a frame uses (a rigid object's world vertices are recomputed only
  // when its pose changed).
  const Object& world() const;

 private:
  CollisionObject() = default;
  std::shared_ptr<const CollisionGeometry> geometry_;
  mutable Object object_;
  mutable bool stale_ = true;
};

struct CollisionRequest {
  DetectOptions options;  // the frame's options (defaults: peelcd's default configuration)
};

struct CollisionResult {
  std::vector<Contact> contacts;  // colliding triangle pairs (A's triangle, B's), sorted
  PairResult pair;                // the pair's details (ROI, PCS, candidates, ...); empty if the
                                  // boxes do not overlap
  Timings timings;
  // A collision: a contact, or one closed object inside the other (pair.relation, no contact).
  bool is_collision() const { return !contacts.empty() || pair.is_collision(); }
  void clear() {
    contacts.clear();
    pair = PairResult{};
    timings = Timings{};
  }
};

// One pair: the contacts of `a` and `b` under `request`, into `result` (cleared first).
// Returns the number of colliding triangle pairs.
std::size_t collide(Detector& detector, const CollisionObject& a, const CollisionObject& b,
                    const CollisionRequest& request, CollisionResult& result);
// The same for plain meshes and poses (world = pose * mesh); convenient, but the meshes are
// validated and moved on every call: an animation loop should keep CollisionObjects.
std::size_t collide(Detector& detector, const Mesh& a, const Eigen::Affine3d& pose_a, const Mesh& b,
                    const Eigen::Affine3d& pose_b, const CollisionRequest& request, CollisionResult& result);

// Many objects: every overlapping pair in one frame, the frame's storage reused from frame to
// frame. Objects are held by pointer: they must outlive the world's use of them. Built on a
// World (peelcd/core/world/world.h): each object is a body with a tree kept across frames; each frame a
// rigid object's body takes its pose, a deforming object's its vertices (read whole: the object
// is changed in place, unannounced; a World used directly can be told which vertices moved).
class CollisionWorld {
 public:
  explicit CollisionWorld(std::shared_ptr<Detector> detector);
  ~CollisionWorld();
  void add(CollisionObject* object);
  void clear();
  // One frame; the result holds one PairResult per overlapping pair (object indices in the
  // order of add()).
  const FrameResult& detect(const DetectOptions& options = {});

 private:
  std::shared_ptr<Detector> detector_;
  std::vector<CollisionObject*> objects_;
  std::unique_ptr<World> world_;
  std::vector<std::uint32_t> bodies_;
  FrameResult result_;
  std::atomic<std::thread::id> owner_{};  // the thread inside add, clear or detect (ExclusiveUse)
};

}  // namespace peelcd
