#include "peelcd/core/mesh.h"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace peelcd {

Vec3 Transform::apply(const Vec3& p) const {
  Vec3 q = p * scale;
  if (degrees != 0.0) {
    // Normalized through its largest component: an axis like (1e300, 1e300, 0), whose norm
    // overflows, still gives its direction.
    const double m = axis.cwiseAbs().maxCoeff();
    if (!(m > 0.0) || !std::isfinite(m)) throw std::invalid_argument("peelcd::Transform: rotation axis is zero or not finite");
    const double rad = degrees * M_PI / 180.0;
    q = Eigen::AngleAxisd(rad, (axis / m).normalized()) * q;
  }
  return q + translate;
}

Mesh transformed(const Mesh& mesh, const Transform& t) {
  Mesh out;
  out.triangles = mesh.triangles;
  out.vertices.reserve(mesh.vertices.size());
  for (const Vec3& p : mesh.vertices) out.vertices.push_back(t.apply(p));
  return out;
}

void validate_mesh(const Mesh& mesh, const std::string& what) {
  if (mesh.triangles.empty())
    throw std::invalid_argument(what + ": the mesh has no triangles");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite())
      throw std::invalid_argument(what + ": vertex " + std::to_string(i) +
                                  " has a NaN or infinite coordinate");
  }
  const std::size_t n = mesh.vertices.size();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (std::uint32_t v : mesh.triangles[f]) {
      if (v >= n)
        throw std::invalid_argument(what + ": triangle " + std::to_string(f) +
                                    " uses vertex " + std::to_string(v) + " but the mesh has " +
                                    std::to_string(n) + " vertices");
    }
  }
}

}  // namespace peelcd
