#include "peelcd/core/image/cpu_peel.h"
#include "peelcd/core/image/id_map.h"

#include <algorithm>
#include <cmath>

namespace peelcd {
namespace {

struct Hit {
  double depth;
  int object;  // 0 = A, 1 = B
  std::uint32_t id;
  double gu, gv;  // depth change per texel step along u and v (world units)
};

// Appends the hits of `mesh`'s triangles with the texel-centre rays of `view`.
void rasterize(const Mesh& mesh, const std::vector<std::uint32_t>* only, int object, const RoiView& view, IdMode ids,
               std::vector<std::vector<Hit>>& texels) {
  const int n = view.resolution;
  const double h = view.half_uv, texel = view.texel();
  const ViewFrame& f = view.frame;
  const std::size_t count = only ? only->size() : mesh.triangles.size();
  for (std::size_t i_tri = 0; i_tri < count; ++i_tri) {
    const auto t = only ? (*only)[i_tri] : std::uint32_t(i_tri);
    Vec3 p[3];
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = mesh.vertices[mesh.triangles[t][k]] - view.center;
      u[k] = p[k].dot(f.u);
      v[k] = p[k].dot(f.v);
    }
    const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
    if (area == 0.0) continue;  // edge-on: no coverage, as in rasterization
    const int i0 = std::max(0, int(std::floor((std::min({u[0], u[1], u[2]}) + h) / texel - 0.5)));
    const int i1 = std::min(n - 1, int(std::ceil((std::max({u[0], u[1], u[2]}) + h) / texel - 0.5)));
    const int j0 = std::max(0, int(std::floor((std::min({v[0], v[1], v[2]}) + h) / texel - 0.5)));
    const int j1 = std::min(n - 1, int(std::ceil((std::max({v[0], v[1], v[2]}) + h) / texel - 0.5)));
    const std::uint32_t id = corner_id(mesh, t, 2, ids);
    // Depth plane z(u, v) of the projected triangle: its gradient per texel.
    double z[3];
    for (int k = 0; k < 3; ++k) z[k] = p[k].dot(f.d);
    const double gu = ((z[1] - z[0]) * (v[2] - v[0]) - (z[2] - z[0]) * (v[1] - v[0])) / area * texel;
    const double gv = ((u[1] - u[0]) * (z[2] - z[0]) - (u[2] - u[0]) * (z[1] - z[0])) / area * texel;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double x = -h + (i + 0.5) * texel, y = -h + (j + 0.5) * texel;
        // Barycentric coordinates of (x, y) in the projected triangle.
        const double w0 = ((u[1] - x) * (v[2] - y) - (u[2] - x) * (v[1] - y)) / area;
        const double w1 = ((u[2] - x) * (v[0] - y) - (u[0] - x) * (v[2] - y)) / area;
        const double w2 = 1.0 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const Vec3 q = w0 * p[0] + w1 * p[1] + w2 * p[2];
        const Vec3 world = q + view.center;
        if ((world.array() < view.box.lo.array()).any() || (world.array() > view.box.hi.array()).any()) continue;
        texels[std::size_t(j) * n + i].push_back({q.dot(f.d), object, id, gu, gv});
      }
  }
}

}  // namespace

CpuPeelResult cpu_peel(const Mesh& a, const Mesh& b, const RoiView& view, IdMode ids, double epsilon,
                       bool a_first, PeelMode mode, double slope, const std::vector<std::uint32_t>* only_a,
                       const std::vector<std::uint32_t>* only_b) {
  const int n = view.resolution;
  std::vector<std::vector<Hit>> texels(std::size_t(n) * n);
  rasterize(a, only_a, 0, view, ids, texels);
  rasterize(b, only_b, 1, view, ids, texels);
  CpuPeelResult r;
  std::vector<Hit> layers;
  for (auto& hits : texels) {
    std::sort(hits.begin(), hits.end(), [](const Hit& x, const Hit& y) { return x.depth < y.depth; });
    layers.clear();
    if (mode == PeelMode::full) {
      layers = hits;
    } else {
      int object = a_first ? 0 : 1;
      double last = -INFINITY;
      for (;;) {
        auto it = std::find_if(hits.begin(), hits.end(),
                               [&](const Hit& h) { return h.object == object && h.depth > last; });
        if (it == hits.end()) break;
        layers.push_back(*it);
        last = it->depth;
        object ^= 1;
      }
    }
    r.layers = std::max(r.layers, int(layers.size()));
    const auto test = [&](const Hit& x, const Hit& y) {
      const double spread = slope * (std::abs(x.gu - y.gu) + std::abs(x.gv - y.gv));
      if (std::abs(y.depth - x.depth) < epsilon + spread)
        r.pcs.push_back(x.object == 0 ? IdPair{x.id, y.id} : IdPair{y.id, x.id});
    };
    // Full mode also pairs the first surface of each same-object run with the first surface of
    // the next run, which is what alternate peeling pairs (see shaders/pcs.comp).
    std::size_t run_start = 0;
    for (std::size_t k = 0; k + 1 < layers.size(); ++k) {
      if (layers[k].object == layers[k + 1].object) continue;
      test(layers[k], layers[k + 1]);
      if (run_start != k) test(layers[run_start], layers[k + 1]);
      run_start = k + 1;
    }
  }
  std::sort(r.pcs.begin(), r.pcs.end());
  r.pcs.erase(std::unique(r.pcs.begin(), r.pcs.end()), r.pcs.end());
  return r;
}

}  // namespace peelcd
