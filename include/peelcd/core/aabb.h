#pragma once
// Axis-aligned boxes: per-object world bounds and ROIs (the intersection of two bounds).
#include "peelcd/core/mesh.h"

#include <limits>

namespace peelcd {

struct Aabb {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (lo.array() > hi.array()).any(); }
  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Vec3 center() const { return 0.5 * (lo + hi); }
  Vec3 extent() const { return hi - lo; }
  // The box grown by d on every side (an empty box stays empty).
  Aabb grown(double d) const {
    Aabb g;
    g.lo = lo - Vec3::Constant(d);
    g.hi = hi + Vec3::Constant(d);
    return g;
  }
  // Closed-box overlap: boxes that only touch overlap (a touching contact must not be lost).
  bool overlaps(const Aabb& o) const {
    return (lo.array() <= o.hi.array()).all() && (o.lo.array() <= hi.array()).all();
  }
};

Aabb bounds(const Mesh& mesh);
Aabb triangle_bounds(const Mesh& mesh, std::uint32_t tri);
// The box of triangle `f`'s corners among `vertices` (triangle_bounds() of a mesh calls it).
Aabb triangle_bounds(const std::vector<Vec3>& vertices, const Tri& f);
// The intersection box; empty() when the boxes do not overlap.
Aabb intersection(const Aabb& a, const Aabb& b);

}  // namespace peelcd
