#pragma once
// Triangle meshes and rigid transforms. Positions are double: geometry is exact-tested on the
// CPU and only becomes float, in ROI-local coordinates, right before upload (gl/pipeline.cpp).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
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

// One object of a frame: its world-space mesh.
struct Object {
  std::string name;
  Mesh mesh;
};

}  // namespace peelcd
