#include "peelcd/core/exact/relation.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace peelcd {


std::string MeshShape::problem() const {
  if (boundary_edges || nonmanifold_edges) {
    std::string s = "open";
    if (boundary_edges) s += ": " + std::to_string(boundary_edges) + " boundary edges";
    if (nonmanifold_edges) s += std::string(boundary_edges ? ", " : ": ") + std::to_string(nonmanifold_edges) + " non-manifold edges";
    return s;
  }
  if (misoriented_edges)
    return "inconsistently oriented: " + std::to_string(misoriented_edges) + " edges traversed twice the same way";
  if (!(signed_volume > 0)) return "inside out: its signed volume is not positive (triangles wound clockwise seen from outside)";
  return {};
}

MeshShape analyse_shape(const Mesh& mesh) {
  MeshShape s;
  struct Edge {
    std::uint32_t lo, hi;
    bool forward;
  };
  std::vector<Edge> edges;
  edges.reserve(3 * mesh.triangles.size());
  double six_v = 0.0;
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = t[k], v = t[(k + 1) % 3];
      if (u != v) edges.push_back({std::min(u, v), std::max(u, v), u < v});
    }
    const Vec3& a = mesh.vertices[t[0]];
    six_v += a.dot((mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a));
  }
  s.signed_volume = six_v / 6.0;
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.lo < y.lo || (x.lo == y.lo && x.hi < y.hi); });
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i, forward = 0;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) forward += edges[j++].forward;
    const std::size_t n = j - i;
    if (n == 1) ++s.boundary_edges;
    else if (n > 2) ++s.nonmanifold_edges;
    else if (forward != 1) ++s.misoriented_edges;
    i = j;
  }
  s.closed = !mesh.triangles.empty() && s.boundary_edges == 0 && s.nonmanifold_edges == 0;
  s.oriented = s.closed && s.misoriented_edges == 0;
  // Components: union-find over the triangles' vertices.
  std::vector<std::uint32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const Tri& t : mesh.triangles) {
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::vector<char> seen(mesh.vertices.size(), 0);
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!used[v]) continue;
    const std::uint32_t r = find(v);
    if (!seen[r]) {
      seen[r] = 1;
      s.component_vertex.push_back(v);
    }
  }
  return s;
}

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// Exact 2D orientation of (p, q, r) in the plane of axes (u, v).
int orient2(double pu, double pv, double qu, double qv, double ru, double rv) {
  return int(CGAL::orientation(K::Point_2(pu, pv), K::Point_2(qu, qv), K::Point_2(ru, rv)));
}

// A triangle projected along axis k, its corners (u, v) in counter-clockwise order, and the
// exact coverage rule: a point strictly inside, or on an edge that is a "left" edge (going
// down) or a "top" edge (horizontal, going left). Around a shared edge or vertex of a
// projected partition, exactly one triangle covers a point: the parity of crossings is exact.
struct Projected {
  double u[3], v[3];
  int facing = 0;  // orientation before the reordering: +1 the normal along +k, -1 against
};

bool project(const Vec3& a, const Vec3& b, const Vec3& c, int k, Projected& p) {
  const int iu = (k + 1) % 3, iv = (k + 2) % 3;
  const Vec3* corner[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    p.u[i] = (*corner[i])[iu];
    p.v[i] = (*corner[i])[iv];
  }
  p.facing = orient2(p.u[0], p.v[0], p.u[1], p.v[1], p.u[2], p.v[2]);
  if (p.facing == 0) return false;  // edge-on along k: no ray crosses it (its neighbours do)
  if (p.facing < 0) {
    std::swap(p.u[1], p.u[2]);
    std::swap(p.v[1], p.v[2]);
  }
  return true;
}

bool covers(const Projected& p, double qu, double qv) {
  for (int e = 0; e < 3; ++e) {
    const int f = (e + 1) % 3;
    const int o = orient2(p.u[e], p.v[e], p.u[f], p.v[f], qu, qv);
    if (o < 0) return false;
    if (o == 0) {
      const bool left = p.v[f] < p.v[e];
      const bool top = p.v[f] == p.v[e] && p.u[f] < p.u[e];
      if (!(left || top)) return false;
    }
  }
  return true;
}

}  // namespace

bool point_inside(const Mesh& container, const Vec3& q) {
  // A ray from q along +z: the parity of the triangles it crosses (exact coverage, exact
  // above/below: q is not on the surface, so no covering triangle's plane holds it).
  int crossings = 0;
  Projected p;
  for (const Tri& t : container.triangles) {
    const Vec3& a = container.vertices[t[0]];
    const Vec3& b = container.vertices[t[1]];
    const Vec3& c = container.vertices[t[2]];
    if (std::max({a.z(), b.z(), c.z()}) < q.z()) continue;
    if (std::min({a.x(), b.x(), c.x()}) > q.x() || std::max({a.x(), b.x(), c.x()}) < q.x()) continue;
    if (std::min({a.y(), b.y(), c.y()}) > q.y() || std::max({a.y(), b.y(), c.y()}) < q.y()) continue;
    if (!project(a, b, c, 2, p) || !covers(p, q.x(), q.y())) continue;
    // The triangle is above q when q is below its plane: on its normal's side when the normal
    // points down (facing < 0), on the other side when it points up.
    const CGAL::Orientation o = CGAL::orientation(K::Point_3(a.x(), a.y(), a.z()), K::Point_3(b.x(), b.y(), b.z()),
                                                  K::Point_3(c.x(), c.y(), c.z()), K::Point_3(q.x(), q.y(), q.z()));
    if (o == CGAL::COPLANAR) continue;  // q on the plane: not covered unless on the surface (excluded)
    const bool below = (o == CGAL::POSITIVE) == (p.facing < 0);
    if (below) ++crossings;
  }
  return crossings % 2 == 1;
}

// Box x lies within box y (closed; both non-empty): only then can x's mesh be inside y's.
static bool within(const Aabb& x, const Aabb& y) {
  return !x.empty() && !y.empty() && (x.lo.array() >= y.lo.array()).all() && (x.hi.array() <= y.hi.array()).all();
}

namespace {

// Every triangle of `x` is a triangle of `y` (the same three corner positions, in any order) and
// the two have as many: one surface, as a mesh and its copy at the same pose.
bool same_surface(const Mesh& x, const Mesh& y) {
  if (x.triangles.size() != y.triangles.size()) return false;
  const auto keys = [](const Mesh& m) {
    std::vector<std::array<double, 9>> out;
    out.reserve(m.triangles.size());
    for (const Tri& t : m.triangles) {
      std::array<Vec3, 3> c = {m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]};
      std::sort(c.begin(), c.end(), [](const Vec3& p, const Vec3& q) {
        return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
      });
      out.push_back({c[0].x(), c[0].y(), c[0].z(), c[1].x(), c[1].y(), c[1].z(), c[2].x(), c[2].y(), c[2].z()});
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  return keys(x) == keys(y);
}

}  // namespace

Relation touching_relation(const Mesh& a, const Mesh& b, const Aabb& ba, const Aabb& bb,
                           const std::vector<Contact>& contacts, std::string& note) {
  // One surface (a mesh and its copy): every triangle touches, none can say on which side the
  // other lies, and the two closed interiors are one: A is inside B (and B inside A).
  if (ba.lo == bb.lo && ba.hi == bb.hi && analyse_shape(b).closed && same_surface(a, b)) {
    note = "A and B coincide (every triangle of one is a triangle of the other): one interior";
    return Relation::a_inside_b;
  }
  for (int side = 0; side < 2; ++side) {
    const Mesh& inner = side == 0 ? a : b;
    const Mesh& outer = side == 0 ? b : a;
    if (!within(side == 0 ? ba : bb, side == 0 ? bb : ba)) continue;
    if (!analyse_shape(outer).closed) continue;
    // A triangle of the inner mesh in no contact is off the outer surface (a positive distance
    // away): its centroid, tested exactly, says on which side all of it lies.
    std::vector<char> touched(inner.triangles.size(), 0);
    for (const Contact& c : contacts) touched[side == 0 ? c.tri_a : c.tri_b] = 1;
    for (std::size_t t = 0; t < inner.triangles.size(); ++t) {
      if (touched[t]) continue;
      const Tri& f = inner.triangles[t];
      const Vec3 centroid = (inner.vertices[f[0]] + inner.vertices[f[1]] + inner.vertices[f[2]]) / 3.0;
      if (!point_inside(outer, centroid)) goto next_side;  // outside: only touching
      note = std::string(side == 0 ? "A" : "B") + " touches " + (side == 0 ? "B" : "A") + "'s surface from inside";
      return side == 0 ? Relation::a_inside_b : Relation::b_inside_a;
    }
  next_side:;
  }
  return Relation::touching;
}

Relation contact_relation(const std::vector<Contact>& contacts) {
  if (contacts.empty()) return Relation::disjoint;
  for (const Contact& c : contacts)
    if (c.kind == ContactKind::crossing) return Relation::crossing;
  return Relation::touching;
}

Relation relate(const Mesh& a, const Mesh& b, const std::vector<Contact>& contacts, std::string& note) {
  return relate(a, b, bounds(a), bounds(b), contacts, note);
}

Relation relate(const Mesh& a, const Mesh& b, const Aabb& ba, const Aabb& bb, const std::vector<Contact>& contacts,
                std::string& note) {
  note.clear();
  if (!contacts.empty()) return contact_relation(contacts);
  // No contact: one is inside the other, or they are disjoint. Only a mesh whose box lies within
  // the other's can be inside it.
  for (int side = 0; side < 2; ++side) {
    const Mesh& inner = side == 0 ? a : b;
    const Mesh& outer = side == 0 ? b : a;
    if (!within(side == 0 ? ba : bb, side == 0 ? bb : ba)) continue;
    const MeshShape container = analyse_shape(outer);
    if (!container.closed) {
      note = std::string(side == 0 ? "B" : "A") + " is " + container.problem() + ": whether " + (side == 0 ? "A" : "B") +
             " is inside it is undefined";
      return Relation::unknown;
    }
    const MeshShape content = analyse_shape(inner);
    std::size_t inside = 0;
    for (const std::uint32_t v : content.component_vertex) inside += point_inside(outer, inner.vertices[v]);
    if (inside > 0) {
      if (inside < content.component_vertex.size())
        note = std::to_string(inside) + " of " + std::to_string(content.component_vertex.size()) + " pieces inside";
      return side == 0 ? Relation::a_inside_b : Relation::b_inside_a;
    }
  }
  return Relation::disjoint;
}

namespace {

struct Crossing {
  std::uint32_t texel;
  float pad = 0;
  double depth;
  std::int8_t step;    // +1 entering, -1 leaving (along the ray)
  std::uint8_t object;  // 0: A, 1: B
};

// One axis at `n` texels across: the volume where both winding numbers are positive, and the
// gradient's k-th component.
void cast_axis(const Mesh& a, const Mesh& b, const Aabb& roi, int k, int n, double& volume, double& gradient_k,
               std::vector<Crossing>& xs, std::vector<float>* per_texel = nullptr) {
  const int iu = (k + 1) % 3, iv = (k + 2) % 3;
  const double u0 = roi.lo[iu], v0 = roi.lo[iv];
  const double hu = (roi.hi[iu] - roi.lo[iu]) / n, hv = (roi.hi[iv] - roi.lo[iv]) / n;
  volume = gradient_k = 0.0;
  if (!(hu > 0) || !(hv > 0) || !(roi.hi[k] > roi.lo[k])) return;
  xs.clear();
  Projected p;
  for (int o = 0; o < 2; ++o) {
    const Mesh& m = o == 0 ? a : b;
    for (const Tri& t : m.triangles) {
      const Vec3& c0 = m.vertices[t[0]];
      const Vec3& c1 = m.vertices[t[1]];
      const Vec3& c2 = m.vertices[t[2]];
      const double umin = std::min({c0[iu], c1[iu], c2[iu]}), umax = std::max({c0[iu], c1[iu], c2[iu]});
      const double vmin = std::min({c0[iv], c1[iv], c2[iv]}), vmax = std::max({c0[iv], c1[iv], c2[iv]});
      // The texel centres the triangle's box may cover (clamped to the grid before any
      // conversion: a triangle far from the box must not overflow an int).
      const auto texel = [n](double x) { return int(std::clamp(x, -2.0, double(n) + 1.0)); };
      const int i0 = std::max(0, texel(std::ceil((umin - u0) / hu - 0.5)) - 1);
      const int i1 = std::min(n - 1, texel(std::floor((umax - u0) / hu - 0.5)) + 1);
      const int j0 = std::max(0, texel(std::ceil((vmin - v0) / hv - 0.5)) - 1);
      const int j1 = std::min(n - 1, texel(std::floor((vmax - v0) / hv - 0.5)) + 1);
      if (i0 > i1 || j0 > j1) continue;
      if (!project(c0, c1, c2, k, p)) continue;
      const Vec3 normal = (c1 - c0).cross(c2 - c0);
      for (int j = j0; j <= j1; ++j) {
        const double qv = v0 + (j + 0.5) * hv;
        for (int i = i0; i <= i1; ++i) {
          const double qu = u0 + (i + 0.5) * hu;
          if (!covers(p, qu, qv)) continue;
          const double depth = c0[k] - (normal[iu] * (qu - c0[iu]) + normal[iv] * (qv - c0[iv])) / normal[k];
          xs.push_back({std::uint32_t(j * n + i), 0.f, depth, std::int8_t(p.facing < 0 ? 1 : -1), std::uint8_t(o)});
        }
      }
    }
  }
  std::sort(xs.begin(), xs.end(), [](const Crossing& x, const Crossing& y) {
    return x.texel < y.texel || (x.texel == y.texel && x.depth < y.depth);
  });
  const double area = hu * hv;
  double length = 0.0, grad = 0.0;
  if (per_texel) per_texel->assign(std::size_t(n) * std::size_t(n), 0.0f);
  for (std::size_t i = 0; i < xs.size();) {
    std::size_t j = i;
    int w[2] = {0, 0};
    double last = 0.0;
    for (; j < xs.size() && xs[j].texel == xs[i].texel; ++j) {
      const Crossing& x = xs[j];
      if (w[0] > 0 && w[1] > 0) {
        length += x.depth - last;
        if (per_texel) (*per_texel)[x.texel] += float(x.depth - last);
      }
      // A's surface inside B: its outward normal's k-component, signed (leaving A along +k
      // means A's normal points along +k).
      if (x.object == 0 && w[1] > 0) grad += x.step > 0 ? -area : area;
      w[x.object] += x.step;
      last = x.depth;
    }
    i = j;
  }
  volume = length * area;
  gradient_k = grad;
}

}  // namespace

VolumeEstimate overlap_volume(const Mesh& a, const Mesh& b, const Aabb& roi, int resolution) {
  VolumeEstimate e;
  e.resolution = resolution;
  e.method = "rays through texel centres along x, y and z over the overlap box (CPU), the volume from z, "
             "the error from the three axes and half the resolution (3x their largest difference, at least one texel column)";
  for (int side = 0; side < 2; ++side) {
    const std::string problem = analyse_shape(side == 0 ? a : b).problem();
    if (!problem.empty()) {
      e.reason = std::string(side == 0 ? "A" : "B") + " is " + problem + ": no intersection volume";
      return e;
    }
  }
  e.known = true;
  if (roi.empty() || resolution < 2) return e;
  std::vector<Crossing> xs;
  double v[3], g[3], half_v = 0.0, half_g = 0.0;
  for (int k = 0; k < 3; ++k) cast_axis(a, b, roi, k, resolution, v[k], g[k], xs);
  cast_axis(a, b, roi, 2, resolution / 2, half_v, half_g, xs);
  e.volume = v[2];
  e.gradient = Vec3(g[0], g[1], g[2]);
  // The estimate: kVolumeErrorFactor times the largest difference to the other three casts, and
  // never less than one texel column of the z cast (a sliver between the rays of every cast).
  const double spread = std::max({std::abs(v[0] - v[2]), std::abs(v[1] - v[2]), std::abs(half_v - v[2])});
  const Vec3 ext = roi.hi - roi.lo;
  const double column = ext.x() * ext.y() * ext.z() / (double(resolution) * double(resolution));
  e.error = std::max(kVolumeErrorFactor * spread, column);
  return e;
}

std::string overlap_lengths(const Mesh& a, const Mesh& b, const Vec3& center, const Vec3& u, const Vec3& v, const Vec3& d,
                            double half_uv, double half_depth, int n, std::vector<float>& out) {
  out.clear();
  for (int side = 0; side < 2; ++side) {
    const std::string problem = analyse_shape(side == 0 ? a : b).problem();
    if (!problem.empty()) return std::string(side == 0 ? "A" : "B") + " is " + problem;
  }
  const auto in_view = [&](const Mesh& m) {
    Mesh r = m;
    for (Vec3& p : r.vertices) {
      const Vec3 q = p - center;
      p = Vec3(u.dot(q), v.dot(q), d.dot(q));
    }
    return r;
  };
  Aabb box;
  box.lo = Vec3(-half_uv, -half_uv, -half_depth);
  box.hi = Vec3(half_uv, half_uv, half_depth);
  std::vector<Crossing> xs;
  double volume = 0.0, gradient = 0.0;
  cast_axis(in_view(a), in_view(b), box, 2, n, volume, gradient, xs, &out);
  return {};
}

double exact_overlap_volume(const Mesh& a, const Mesh& b) {
  using EK = CGAL::Exact_predicates_exact_constructions_kernel;
  using SM = CGAL::Surface_mesh<EK::Point_3>;
  const auto to_sm = [](const Mesh& m, const char* which) {
    SM sm;
    std::vector<SM::Vertex_index> vs;
    vs.reserve(m.vertices.size());
    for (const Vec3& p : m.vertices) vs.push_back(sm.add_vertex(EK::Point_3(p.x(), p.y(), p.z())));
    for (const Tri& t : m.triangles)
      if (sm.add_face(vs[t[0]], vs[t[1]], vs[t[2]]) == SM::null_face())
        throw std::runtime_error(std::string("exact_overlap_volume(): ") + which + " is not a manifold surface");
    return sm;
  };
  SM sa = to_sm(a, "A"), sb = to_sm(b, "B"), out;
  if (!CGAL::Polygon_mesh_processing::corefine_and_compute_intersection(sa, sb, out))
    throw std::runtime_error("exact_overlap_volume(): CGAL's corefinement could not build the intersection");
  if (out.number_of_faces() == 0) return 0.0;
  return CGAL::to_double(CGAL::Polygon_mesh_processing::volume(out));
}

}  // namespace peelcd
