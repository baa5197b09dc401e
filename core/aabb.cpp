#include "peelcd/core/aabb.h"

namespace peelcd {

Aabb bounds(const Mesh& mesh) {
  Aabb b;
  for (const Vec3& p : mesh.vertices) b.extend(p);
  return b;
}

Aabb triangle_bounds(const std::vector<Vec3>& v, const Tri& f) {
  Aabb b;
  b.lo = v[f[0]].cwiseMin(v[f[1]]).cwiseMin(v[f[2]]);
  b.hi = v[f[0]].cwiseMax(v[f[1]]).cwiseMax(v[f[2]]);
  return b;
}

Aabb triangle_bounds(const Mesh& mesh, std::uint32_t tri) { return triangle_bounds(mesh.vertices, mesh.triangles[tri]); }

Aabb intersection(const Aabb& a, const Aabb& b) {
  Aabb r;
  r.lo = a.lo.cwiseMax(b.lo);
  r.hi = a.hi.cwiseMin(b.hi);
  return r;
}

}  // namespace peelcd
