// Proximity (peelcd/core/exact/proximity.h): triangle distances and the pairs within a margin.
#include "peelcd/core/exact/proximity.h"

#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/pairs.h"
#include "peelcd/core/exact/self.h"

#include <algorithm>

namespace peelcd {
namespace {

// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = va + vb + vc;
  if (!(denom > 0)) {  // a degenerate triangle: its closest edge point
    Vec3 best = a;
    double bd = (p - a).squaredNorm();
    for (const auto& [u, w] : {std::pair{a, b}, {b, c}, {c, a}}) {
      const Vec3 e = w - u;
      const double l = e.squaredNorm();
      const double t = l > 0 ? std::clamp((p - u).dot(e) / l, 0.0, 1.0) : 0.0;
      const Vec3 x = u + t * e;
      if ((p - x).squaredNorm() < bd) bd = (p - x).squaredNorm(), best = x;
    }
    return best;
  }
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

// The closest points of segments [p1, q1] and [p2, q2] (Ericson 5.1.9).
void closest_segments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3& c1, Vec3& c2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= 0 && e <= 0) {
  } else if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
}

}  // namespace

double triangle_distance(const TriangleCorners& a, const TriangleCorners& b, Vec3& p, Vec3& q) {
  Contact c;
  if (test_triangle_pair(a, b, c)) {
    p = q = c.p;
    return 0.0;
  }
  double best = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Vec3& x, const Vec3& y) {
    const double d = (x - y).squaredNorm();
    if (d < best) best = d, p = x, q = y;
  };
  for (int k = 0; k < 3; ++k) {
    consider(a[k], closest_on_triangle(a[k], b[0], b[1], b[2]));
    consider(closest_on_triangle(b[k], a[0], a[1], a[2]), b[k]);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Vec3 x, y;
      closest_segments(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], x, y);
      consider(x, y);
    }
  return std::sqrt(best);
}

namespace {

void finish(Proximity& r) {
  std::sort(r.pairs.begin(), r.pairs.end(), [](const NearPair& x, const NearPair& y) {
    return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
  });
  for (const NearPair& n : r.pairs)
    if (n.distance < r.distance) r.distance = n.distance, r.p = n.p, r.q = n.q;
}


}  // namespace

namespace {

// Every triangle of `a` against a tree over `b`'s, each of a's boxes grown by the margin; `skip`
// drops couples (a self search's repeats and adjacent couples).
template <class Skip>
Proximity search_near(const Mesh& a, const Mesh& b, const Bvh& tree, double margin, Skip&& skip) {
  Proximity r;
  if (a.triangles.empty() || b.triangles.empty()) return r;
  std::vector<std::uint32_t> found;
  for (std::uint32_t ta = 0; ta < a.triangles.size(); ++ta) {
    const TriangleCorners ca = corners(a, ta);
    tree.query(triangle_bounds(a, ta).grown(margin), found);
    for (const std::uint32_t tb : found) {
      if (skip(ta, tb)) continue;
      NearPair n;
      n.distance = triangle_distance(ca, corners(b, tb), n.p, n.q);
      if (n.distance > margin) continue;
      n.tri_a = ta;
      n.tri_b = tb;
      r.pairs.push_back(n);
    }
  }
  finish(r);
  return r;
}

}  // namespace

Proximity near_pairs(const Mesh& a, const Mesh& b, const Bvh& tree_b, double margin) {
  return search_near(a, b, tree_b, margin, [](std::uint32_t, std::uint32_t) { return false; });
}

Proximity near_self_pairs(const Mesh& m, const Bvh& tree, const std::vector<std::uint32_t>& rep, double margin) {
  return search_near(m, m, tree, margin,
                     [&](std::uint32_t t, std::uint32_t u) { return u <= t || triangles_adjacent(m, rep, t, u); });
}

Proximity near_among(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& candidates, double margin) {
  Proximity r;
  for (const std::uint64_t c : candidates) {
    NearPair n;
    n.tri_a = pair_a(c);
    n.tri_b = pair_b(c);
    n.distance = triangle_distance(corners(a, n.tri_a), corners(b, n.tri_b), n.p, n.q);
    if (n.distance <= margin) r.pairs.push_back(n);
  }
  finish(r);
  return r;
}

Proximity near_pairs(const Mesh& a, const Mesh& b, double margin) {
  Bvh tree;
  tree.build(b.vertices, b.triangles);
  return near_pairs(a, b, tree, margin);
}

Proximity near_self_pairs(const Mesh& m, const std::vector<std::uint32_t>& rep, double margin) {
  Bvh tree;
  tree.build(m.vertices, m.triangles);
  return near_self_pairs(m, tree, rep, margin);
}

}  // namespace peelcd
