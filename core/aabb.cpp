#include "peelcd/core/aabb.h"

namespace peelcd {

Aabb bounds(const Mesh& mesh) {
  Aabb b;
  for (const Vec3& p : mesh.vertices) b.extend(p);
  return b;
}

Aabb triangle_bounds(const Mesh& mesh, std::uint32_t tri) {
  Aabb b;
  for (std::uint32_t v : mesh.triangles[tri]) b.extend(mesh.vertices[v]);
  return b;
}

Aabb intersection(const Aabb& a, const Aabb& b) {
  Aabb r;
  r.lo = a.lo.cwiseMax(b.lo);
  r.hi = a.hi.cwiseMin(b.hi);
  return r;
}

}  // namespace peelcd
