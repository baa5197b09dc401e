#pragma once
// Triangle meshes and rigid transforms. Positions are double: geometry is exact-tested on the
// CPU and only becomes float, in ROI-local coordinates, right before upload (gl/pipeline.cpp).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace peelcd {

using Vec3 = Eigen::Vector3d;
using Tri = std::array<std::uint32_t, 3>;

struct Mesh {
  std::vector<Vec3> vertices;  // #V positions
  std::vector<Tri> triangles;  // #F vertex indices; order = file order (IDs refer to it)
};

// Applied as: scale, then rotate about `axis` by `degrees`, then translate.
struct Transform {
  double scale = 1.0;
  Vec3 axis = Vec3(0, 0, 1);
  double degrees = 0.0;
  Vec3 translate = Vec3::Zero();

  Vec3 apply(const Vec3& p) const;
};

// Returns `mesh` with every vertex moved by `t`; the triangles are unchanged.
Mesh transformed(const Mesh& mesh, const Transform& t);

// Throws std::invalid_argument naming `what` if an index is out of range, a coordinate is not
// finite, or there are no triangles.
void validate_mesh(const Mesh& mesh, const std::string& what);

// Optional for an object: it is `shape` moved rigidly, world = pose * local (a rotation and a
// translation, possibly with a uniform scale). The GL pipeline then keeps `shape` on the GPU
// across frames (uploaded once per ID mode, while some object holds the shared_ptr) and per ROI
// uploads only the indices of the triangles touching it, moved by the pose.
struct RigidMotion {
  std::shared_ptr<const Mesh> shape;
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
};

// Optional for an object whose triangles stay while its vertices move from frame to frame (a
// deforming body of the World): its world-space mesh is `*source` (the object's own `mesh` is
// left empty; drawn_mesh()). The GL stage's batch keeps the triangles on the GPU (uploaded once
// per `topology` and ID mode, while something holds `topology`: whoever changes the triangles
// makes a new one) and uploads the vertices once a batch.
struct MovingMesh {
  std::shared_ptr<const void> topology;
  const Mesh* source = nullptr;
};

// One object of a frame: its world-space mesh (always, but for a moving mesh: the CPU stages
// use it), and optionally the rigid motion that produced it.
struct Object {
  std::string name;
  Mesh mesh;
  std::optional<RigidMotion> rigid;
  std::optional<MovingMesh> moving;
  // Test the object against itself too (self-collision; DetectOptions::self asks it for all).
  bool self = false;
};

// An object named `name` of `mesh`, neither rigid nor moving nor asking for self-collision.
inline Object named_object(std::string name, Mesh mesh) {
  Object o;
  o.name = std::move(name);
  o.mesh = std::move(mesh);
  return o;
}

// The world-space mesh an object's triangles are drawn from: a moving mesh's source, else its own.
inline const Mesh& drawn_mesh(const Object& o) { return o.moving && o.moving->source ? *o.moving->source : o.mesh; }

}  // namespace peelcd
