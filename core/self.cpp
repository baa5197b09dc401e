#include "peelcd/core/self.h"

#include "peelcd/core/id_map.h"

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <numeric>

namespace peelcd {

const char* to_string(SelfAdjacency adjacency) { return adjacency == SelfAdjacency::index ? "index" : "position"; }

std::optional<SelfAdjacency> parse_self_adjacency(const std::string& text) {
  if (text == "index") return SelfAdjacency::index;
  if (text == "position") return SelfAdjacency::position;
  return std::nullopt;
}

void vertex_representatives(const Mesh& mesh, SelfAdjacency adjacency, std::vector<std::uint32_t>& out) {
  const std::size_t n = mesh.vertices.size();
  out.resize(n);
  std::iota(out.begin(), out.end(), 0u);
  if (adjacency == SelfAdjacency::index || n < 2) return;
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  const auto less = [&](std::uint32_t i, std::uint32_t j) {
    const Vec3& p = mesh.vertices[i];
    const Vec3& q = mesh.vertices[j];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return i < j;
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < n; ++k)
    if (mesh.vertices[order[k]] == mesh.vertices[order[k - 1]]) out[order[k]] = out[order[k - 1]];
}

bool triangles_adjacent(const Mesh& mesh, const std::vector<std::uint32_t>& rep, std::uint32_t t, std::uint32_t u) {
  const Tri& a = mesh.triangles[t];
  const Tri& b = mesh.triangles[u];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (rep[a[i]] == rep[b[j]]) return true;
  return false;
}

namespace {
struct SweepBox {
  double lo[3], hi[3];
  std::uint32_t tri;
};
}  // namespace

void self_overlap_pairs(const Mesh& mesh, const std::vector<std::uint32_t>* tris, const std::vector<std::uint32_t>& rep,
                        std::vector<std::uint64_t>& out) {
  const std::size_t n = tris ? tris->size() : mesh.triangles.size();
  std::vector<SweepBox> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t t = tris ? (*tris)[i] : std::uint32_t(i);
    const Tri& f = mesh.triangles[t];
    SweepBox& b = boxes[i];
    for (int k = 0; k < 3; ++k) {
      const double x = mesh.vertices[f[0]][k], y = mesh.vertices[f[1]][k], z = mesh.vertices[f[2]][k];
      b.lo[k] = std::min({x, y, z});
      b.hi[k] = std::max({x, y, z});
    }
    b.tri = t;
  }
  // Along the axis of largest spread: a sheet lying in a plane would sweep badly along its normal.
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = i ? std::min(lo[k], boxes[i].lo[k]) : boxes[i].lo[k];
      hi[k] = i ? std::max(hi[k], boxes[i].hi[k]) : boxes[i].hi[k];
    }
  int ax = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[ax] - lo[ax]) ax = k;
  std::sort(boxes.begin(), boxes.end(), [ax](const SweepBox& x, const SweepBox& y) { return x.lo[ax] < y.lo[ax]; });
  const int o1 = (ax + 1) % 3, o2 = (ax + 2) % 3;
  for (std::size_t i = 0; i < n; ++i) {
    const SweepBox& x = boxes[i];
    for (std::size_t k = i + 1; k < n && !(boxes[k].lo[ax] > x.hi[ax]); ++k) {
      const SweepBox& y = boxes[k];
      if (x.hi[o1] < y.lo[o1] || y.hi[o1] < x.lo[o1] || x.hi[o2] < y.lo[o2] || y.hi[o2] < x.lo[o2]) continue;
      if (triangles_adjacent(mesh, rep, x.tri, y.tri)) continue;
      out.push_back(x.tri < y.tri ? pack_pair(x.tri, y.tri) : pack_pair(y.tri, x.tri));
    }
  }
}

void self_candidates(const Mesh& mesh, const std::vector<std::uint32_t>& rep, std::vector<std::uint64_t>& pairs) {
  std::size_t w = 0;
  for (const std::uint64_t p : pairs) {
    std::uint32_t t = pair_a(p), u = pair_b(p);
    if (t == u || triangles_adjacent(mesh, rep, t, u)) continue;
    if (u < t) std::swap(t, u);
    pairs[w++] = pack_pair(t, u);
  }
  pairs.resize(w);
  std::vector<std::uint64_t> scratch;
  sort_unique_pairs(pairs, scratch);
}

std::vector<std::uint64_t> exact_self_pairs(const Mesh& mesh, SelfAdjacency adjacency) {
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::uint32_t>;
  std::vector<std::uint32_t> rep;
  vertex_representatives(mesh, adjacency, rep);
  std::vector<Box> boxes;
  boxes.reserve(mesh.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = hi[k] = mesh.vertices[mesh.triangles[t][0]][k];
      for (int c = 1; c < 3; ++c) {
        lo[k] = std::min(lo[k], mesh.vertices[mesh.triangles[t][c]][k]);
        hi[k] = std::max(hi[k], mesh.vertices[mesh.triangles[t][c]][k]);
      }
    }
    boxes.emplace_back(lo, hi, t);
  }
  std::vector<std::uint64_t> out;
  CGAL::box_self_intersection_d(
      boxes.begin(), boxes.end(),
      [&](const Box& x, const Box& y) {
        const std::uint32_t t = std::min(x.info(), y.info()), u = std::max(x.info(), y.info());
        if (triangles_adjacent(mesh, rep, t, u)) return;
        if (triangles_intersect(corners(mesh, t), corners(mesh, u))) out.push_back(pack_pair(t, u));
      },
      std::ptrdiff_t(10), CGAL::Box_intersection_d::CLOSED);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace peelcd
