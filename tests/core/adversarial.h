#pragma once
// Seeded generator of adversarial triangle pairs for the narrow phase: the configurations where
// floating-point tests go wrong. Coplanar and touching cases are built on an integer lattice,
// so they are exactly what they claim before scaling; the scale and offset (powers of ten, not
// exact) then turn some of them into near-coplanar or near-touching cases, which is the point.
#include "peelcd/core/exact/narrow_phase.h"

#include <random>

namespace peelcd::test {

enum class Family {
  generic,           // random triangles in a small box: crossing or disjoint
  coplanar_overlap,  // same lattice plane, overlapping
  coplanar_touch,    // same plane, sharing an edge or a vertex, or separated by a hair
  shared_vertex,     // a common corner, otherwise random
  shared_edge,       // a common edge, folded
  point_touch,       // a corner of B on A's interior or edge, B on one side
  near_coplanar,     // B = A's plane moved by a relative 1e-12 .. 1e-16, overlapping in projection
  sliver,            // a needle or a zero-area triangle (collinear or repeated corners)
  count
};
const char* const kFamilyNames[] = {"generic",     "coplanar overlap", "coplanar touch", "shared vertex", "shared edge",
                                    "point touch", "near-coplanar",    "sliver"};

struct AdversarialCase {
  Family family;
  TriangleCorners a, b;
  double scale, offset;
};

class AdversarialGenerator {
 public:
  explicit AdversarialGenerator(std::uint64_t seed) : rng_(seed) {}

  AdversarialCase next() {
    AdversarialCase c;
    c.family = Family(pick(int(Family::count)));
    const double scales[] = {1.0, 1e-6, 1e6, 1.0};
    const double offsets[] = {0.0, 0.0, 1e6, 1e3};
    c.scale = scales[pick(4)];
    c.offset = offsets[pick(4)];
    build(c);
    const Vec3 off = Vec3::Constant(c.offset);
    for (Vec3& p : c.a) p = p * c.scale + off;
    for (Vec3& p : c.b) p = p * c.scale + off;
    return c;
  }

 private:
  std::mt19937_64 rng_;
  int pick(int n) { return int(rng_() % std::uint64_t(n)); }
  double lattice() { return double(pick(17) - 8); }                  // integers in [-8, 8]
  Vec3 lattice_point() { return Vec3(lattice(), lattice(), lattice()); }
  double unit() { return std::uniform_real_distribution<double>(-1, 1)(rng_); }
  Vec3 random_point() { return Vec3(unit(), unit(), unit()); }

  // A lattice point of the plane n.p = c with n in {x, y, z, x+y+z}: exact.
  Vec3 plane_point(int plane, double c) {
    Vec3 p = lattice_point();
    if (plane < 3) p[plane] = c;
    else p.z() = c - p.x() - p.y();
    return p;
  }

  void build(AdversarialCase& c) {
    TriangleCorners& a = c.a;
    TriangleCorners& b = c.b;
    switch (c.family) {
      case Family::generic:
        for (Vec3& p : a) p = random_point();
        for (Vec3& p : b) p = random_point();
        break;
      case Family::coplanar_overlap:
      case Family::coplanar_touch: {
        const int plane = pick(4);
        const double k = lattice();
        for (Vec3& p : a) p = plane_point(plane, k);
        if (c.family == Family::coplanar_overlap) {
          for (Vec3& p : b) p = plane_point(plane, k);
          b[0] = (a[0] + a[1] + a[2]) / 3.0;  // inside A (rounded; near-exact): overlap or graze
        } else {
          b = {a[pick(3)], a[pick(3)], plane_point(plane, k)};  // shares an edge, a vertex or less
        }
        break;
      }
      case Family::shared_vertex:
        for (Vec3& p : a) p = lattice_point();
        b = {a[pick(3)], lattice_point(), lattice_point()};
        break;
      case Family::shared_edge: {
        for (Vec3& p : a) p = lattice_point();
        const int i = pick(3);
        b = {a[i], a[(i + 1) % 3], lattice_point()};
        break;
      }
      case Family::point_touch: {
        for (Vec3& p : a) p = lattice_point();
        // Dyadic barycentric weights: the point is exactly on A (interior, or an edge if 0).
        const double w0 = pick(5) / 4.0, w1 = pick(int(5 - 4 * w0)) / 4.0, w2 = 1.0 - w0 - w1;
        const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]);
        const double side = pick(2) ? 1.0 : -1.0;
        b = {w0 * a[0] + w1 * a[1] + w2 * a[2], a[0] + side * n + lattice_point() * 0.25,
             a[1] + side * n + lattice_point() * 0.25};
        break;
      }
      case Family::near_coplanar: {
        for (Vec3& p : a) p = random_point();
        const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]).normalized();
        const double eps[] = {1e-12, 1e-13, 1e-14, 1e-15, 1e-16, 0.0};
        const double h = eps[pick(6)] * (pick(2) ? 1 : -1);
        const Vec3 centre = (a[0] + a[1] + a[2]) / 3.0;
        for (int i = 0; i < 3; ++i) b[i] = centre + (a[(i + 1) % 3] - centre) * 0.9 + n * h;
        break;
      }
      case Family::sliver: {
        for (Vec3& p : a) p = lattice_point();
        const Vec3 p = lattice_point(), q = lattice_point() * 2.0;
        switch (pick(4)) {
          case 0: b = {p, q, (p + q) * 0.5}; break;                   // collinear
          case 1: b = {p, p, q}; break;                               // repeated corner
          case 2: b = {p, p, p}; break;                               // a point
          default: b = {p, q, (p + q) * 0.5 + Vec3(0, 0, 1e-9)}; break;  // a needle
        }
        if (pick(2)) std::swap(a, b);
        break;
      }
      case Family::count: break;
    }
  }
};

}  // namespace peelcd::test
