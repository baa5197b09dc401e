#include "peelcd/core/primitives.h"

#include <cmath>
#include <stdexcept>

namespace peelcd {

Mesh make_box(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  // Two triangles per face, counter-clockwise from outside.
  m.triangles = {{0, 2, 1}, {1, 2, 3},   // z = lo
                 {4, 5, 6}, {5, 7, 6},   // z = hi
                 {0, 1, 4}, {1, 5, 4},   // y = lo
                 {2, 6, 3}, {3, 6, 7},   // y = hi
                 {0, 4, 2}, {2, 4, 6},   // x = lo
                 {1, 3, 5}, {3, 7, 5}};  // x = hi
  return m;
}

Mesh make_uv_sphere(const Vec3& center, double radius, int stacks, int slices) {
  if (stacks < 2 || slices < 3) throw std::invalid_argument("peelcd::make_uv_sphere(): too few stacks or slices");
  Mesh m;
  m.vertices.push_back(center + Vec3(0, 0, radius));  // north pole
  for (int i = 1; i < stacks; ++i) {
    const double th = M_PI * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double ph = 2.0 * M_PI * j / slices;
      m.vertices.push_back(center + radius * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  }
  m.vertices.push_back(center - Vec3(0, 0, radius));  // south pole
  const auto ring = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * slices + (j % slices)); };
  const std::uint32_t south = std::uint32_t(m.vertices.size() - 1);
  for (int j = 0; j < slices; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < slices; ++j) m.triangles.push_back({ring(stacks - 1, j), south, ring(stacks - 1, j + 1)});
  return m;
}

Mesh make_grid(const Vec3& origin, const Vec3& e1, const Vec3& e2, int n1, int n2) {
  if (n1 < 1 || n2 < 1) throw std::invalid_argument("peelcd::make_grid(): need at least one quad");
  Mesh m;
  for (int j = 0; j <= n2; ++j)
    for (int i = 0; i <= n1; ++i) m.vertices.push_back(origin + e1 * (double(i) / n1) + e2 * (double(j) / n2));
  const auto at = [&](int i, int j) { return std::uint32_t(j * (n1 + 1) + i); };
  for (int j = 0; j < n2; ++j)
    for (int i = 0; i < n1; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

}  // namespace peelcd

namespace peelcd {

Mesh make_folded_sheet(int n, double fold, double sag) {
  // u runs along the sheet: [0, 1/3] the bottom layer (z = 0, x from 0 to 1), [1/3, 2/3] a half
  // circle of radius fold / 2 at x = 1 (the crease), [2/3, 1] the top layer back over the bottom
  // (z = fold), lowered by a bump of depth `sag` centred over the bottom layer's middle.
  const double r = fold / 2;
  const int nu = 3 * n, nv = n;
  const auto at = [&](double u, double y) {
    if (u <= 1.0 / 3) return Vec3(3 * u, y, 0.0);
    if (u < 2.0 / 3) {
      const double a = M_PI * (3 * u - 1) - M_PI / 2;  // -pi/2 .. pi/2
      return Vec3(1.0 + r * std::cos(a), y, r + r * std::sin(a));
    }
    const double x = 1.0 - (3 * u - 2);
    const double d2 = (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5);
    return Vec3(x, y, fold - sag * std::exp(-d2 / 0.04));
  };
  return make_grid_surface(nu, nv, at);
}

Mesh make_grid_surface(int nu, int nv, const std::function<Vec3(double, double)>& at) {
  Mesh m;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) m.vertices.push_back(at(double(i) / nu, double(j) / nv));
  const auto id = [nu](int i, int j) { return std::uint32_t(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

Mesh make_crumpled_cloth(int n, double t) {
  return make_grid_surface(n, n, [t](double u, double v) {
    const double x = 2 * u - 1, y = 2 * v - 1;
    // Tangential waves steeper than the identity: the parameter plane folds over itself.
    const double xs = x + 0.07 * std::sin(23 * y + t) + 0.05 * std::sin(37 * x + 1.3 * t);
    const double ys = y + 0.07 * std::sin(19 * x - t) + 0.05 * std::sin(31 * y + 0.7 * t);
    const double h = 0.03 * std::sin(29 * x + 17 * y + 2 * t);  // each layer's height over the ball
    return Vec3((1.05 + h) * Vec3(1.3 * xs, 1.3 * ys, 1.0).normalized());
  });
}

}  // namespace peelcd
