// peelcd::Bvh (peelcd/core/exact/bvh.h): the tree's structure and float boxes, queries, refits (whole,
// partial, in ranges), the two-tree traversal through a relative pose, its split into tasks, the
// self traversal: each against a brute-force scan.
#include "peelcd/core/exact/bvh.h"
#include "exact/bvh_traverse.h"  // the library's own traversals (core/ is on this target's path)
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/self.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <random>
#include <set>

using namespace peelcd;

namespace {

Eigen::Affine3d pose(double angle, const Vec3& axis, const Vec3& t) {
  Eigen::Affine3d p = Eigen::Affine3d::Identity();
  p.translate(t);
  p.rotate(Eigen::AngleAxisd(angle, axis.normalized()));
  return p;
}

// The couples of a's and b's triangles whose exact boxes overlap (closed) both in A's frame and in
// B's (the traversal separates boxes along either frame's axes).
std::set<std::pair<std::uint32_t, std::uint32_t>> scan(const Mesh& a, const Eigen::Affine3d& pa, const Mesh& b,
                                                       const Eigen::Affine3d& pb) {
  const Eigen::Affine3d b_to_a = pa.inverse() * pb, a_to_b = b_to_a.inverse();
  const auto box_of = [](const Mesh& m, const Eigen::Affine3d& p, std::uint32_t t) {
    Aabb box;
    for (const std::uint32_t v : m.triangles[t]) box.extend(p * m.vertices[v]);
    return box;
  };
  std::set<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t x = 0; x < a.triangles.size(); ++x)
    for (std::uint32_t y = 0; y < b.triangles.size(); ++y)
      if (box_of(a, Eigen::Affine3d::Identity(), x).overlaps(box_of(b, b_to_a, y)) &&
          box_of(b, Eigen::Affine3d::Identity(), y).overlaps(box_of(a, a_to_b, x)))
        out.emplace(x, y);
  return out;
}

// The tree's wide view against its binary nodes: every wide node stands for an internal node
// whose slots are its grandchildren (a leaf child its own slot), each slot's box its node's box,
// each leaf and each even-depth internal node in exactly one slot (the root excepted), a leaf's
// slot naming its leaf, and every leaf's bound its node's box.
void check_wide(const Bvh& t) {
  const auto& nodes = t.nodes();
  const auto& wide = t.wide();
  for (const BvhNode& n : nodes)
    if (n.leaf())
      for (int j = 0; j < 3; ++j) {
        REQUIRE(t.leaf(n).bound.lo[j] == n.box.lo[j]);
        REQUIRE(t.leaf(n).bound.hi[j] == n.box.hi[j]);
      }
  if (nodes.empty() || nodes[0].leaf()) {
    REQUIRE(wide.empty());
    return;
  }
  REQUIRE(t.wide_of(0) == 0);
  std::vector<int> seen(nodes.size(), 0);
  for (std::uint32_t w = 0; w < wide.size(); ++w) {
    const BvhWideNode& x = wide[w];
    REQUIRE(t.wide_of(x.node) == w);
    std::vector<std::uint32_t> want;
    for (const std::uint32_t c : {x.node + 1, nodes[x.node].first}) {
      if (nodes[c].leaf()) {
        want.push_back(c);
      } else {
        REQUIRE(t.wide_of(c) == kBvhWideNone);
        want.push_back(c + 1);
        want.push_back(nodes[c].first);
      }
    }
    for (std::uint32_t k = 0; k < 4; ++k) {
      if (k >= want.size()) {
        REQUIRE(x.child[k] == kBvhWideNone);
        REQUIRE(x.lo[0][k] > x.hi[0][k]);  // empty
        continue;
      }
      const std::uint32_t n = want[k];
      ++seen[n];
      REQUIRE(x.child[k] == (nodes[n].leaf() ? (kBvhWideLeaf | nodes[n].first) : t.wide_of(n)));
      for (int j = 0; j < 3; ++j) {
        REQUIRE(x.lo[j][k] == nodes[n].box.lo[j]);
        REQUIRE(x.hi[j][k] == nodes[n].box.hi[j]);
      }
    }
  }
  for (std::uint32_t n = 1; n < nodes.size(); ++n)
    if (nodes[n].leaf() || t.wide_of(n) != kBvhWideNone) REQUIRE(seen[n] == 1);
}

}  // namespace

TEST_CASE("Bvh: the wide view holds the binary nodes' boxes after builds, refits and partial refits", "[bvh]") {
  Mesh m = make_grid(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 37, 23);
  Bvh t;
  for (const std::size_t n : {1u, 8u, 9u, 17u, 40u, 333u}) {  // a lone leaf, one full leaf, then deeper
    Mesh small = m;
    small.triangles.resize(n);
    t.build(small.vertices, small.triangles);
    check_wide(t);
  }
  t.build(m.vertices, m.triangles);
  check_wide(t);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-0.2, 0.2);
  for (Vec3& v : m.vertices) v.z() += d(rng);
  // A whole refit leaves the view stale; keep_wide_if_still() syncs it only once the tree has
  // not changed between two calls; a partial refit keeps a fresh view fresh.
  t.keep_wide_if_still();
  t.refit(m.vertices, m.triangles);
  CHECK_FALSE(t.wide_fresh());
  t.keep_wide_if_still();  // changed since the last call
  CHECK_FALSE(t.wide_fresh());
  t.keep_wide_if_still();  // unchanged since
  REQUIRE(t.wide_fresh());
  check_wide(t);
  for (Vec3& v : m.vertices) v.z() -= 0.5 * d(rng);
  t.refit(m.vertices, m.triangles);
  t.sync_wide();
  check_wide(t);
  std::vector<std::uint32_t> changed;
  for (std::uint32_t k = 0; k < 40; ++k) {
    const std::uint32_t v = std::uint32_t(k * 31 % m.vertices.size());
    m.vertices[v] += Vec3(d(rng), d(rng), 3 * d(rng));
    for (std::uint32_t f = 0; f < m.triangles.size(); ++f)
      for (const std::uint32_t c : m.triangles[f])
        if (c == v) changed.push_back(f);
  }
  t.refit(m.vertices, m.triangles, changed);
  REQUIRE(t.wide_fresh());
  check_wide(t);
}

TEST_CASE("Bvh: every triangle once, boxes enclose their children, queries equal a scan", "[bvh]") {
  const Mesh m = make_uv_sphere(Vec3(0.1, -0.2, 0.3), 1.0, 23, 31);
  Bvh t;
  t.build(m.vertices, m.triangles);
  std::vector<std::uint32_t> seen(t.order());
  std::sort(seen.begin(), seen.end());
  for (std::uint32_t i = 0; i < seen.size(); ++i) REQUIRE(seen[i] == i);
  const auto& nodes = t.nodes();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].leaf()) {
      CHECK(nodes[i].count <= kBvhLeafSize);
      continue;
    }
    for (const std::size_t c : {i + 1, std::size_t(nodes[i].first)}) {
      CHECK(t.parent(std::uint32_t(c)) == i);
      CHECK((nodes[i].box.aabb().lo.array() <= nodes[c].box.aabb().lo.array()).all());
      CHECK((nodes[i].box.aabb().hi.array() >= nodes[c].box.aabb().hi.array()).all());
    }
  }
  // Float boxes enclose the exact ones; the root's exact box is the corners' box.
  for (std::uint32_t f = 0; f < m.triangles.size(); ++f) {
    const Aabb exact = triangle_bounds(m, f), got = t.triangle_box(f).aabb();
    REQUIRE(((got.lo.array() <= exact.lo.array()).all() && (got.hi.array() >= exact.hi.array()).all()));
    REQUIRE(((exact.lo - got.lo).cwiseAbs().maxCoeff() < 1e-6 && (got.hi - exact.hi).cwiseAbs().maxCoeff() < 1e-6));
  }
  // At every scale, and across zero, subnormals and float's limit.
  for (const double d : {0.0, 1e-45, -1e-45, 1e-40, 0.1, -0.1, 1.0 / 3.0, -2.0 / 3.0, 1e10 + 0.3, -7e20, 1e36, 3e38, -3.4e38, 1e300, -1e300}) {
    CHECK(double(FBox::down(d)) <= d);
    CHECK(double(FBox::up(d)) >= d);
  }
  CHECK(t.box().lo == bounds(m).lo);
  CHECK(t.box().hi == bounds(m).hi);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.3, 1.3);
  for (int q = 0; q < 50; ++q) {
    Aabb box;
    box.extend(Vec3(u(rng), u(rng), u(rng)));
    box.extend(Vec3(u(rng), u(rng), u(rng)));
    std::vector<std::uint32_t> got, want;
    t.query(box, got);
    for (std::uint32_t f = 0; f < m.triangles.size(); ++f)
      if (triangle_bounds(m, f).overlaps(box)) want.push_back(f);
    // Every exact answer; any other within float rounding of the box.
    REQUIRE(std::includes(got.begin(), got.end(), want.begin(), want.end()));
    for (const std::uint32_t f : got) {
      Aabb grown = box;
      grown.lo -= Vec3::Constant(1e-6);
      grown.hi += Vec3::Constant(1e-6);
      REQUIRE(triangle_bounds(m, f).overlaps(grown));
    }
  }
}

TEST_CASE("Bvh: a partial refit gives the boxes of a full one", "[bvh]") {
  Mesh m = make_grid(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 40, 40);
  Bvh partial, full;
  partial.build(m.vertices, m.triangles);
  full.build(m.vertices, m.triangles);
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(m.vertices.size() - 1));
  for (int round = 0; round < 5; ++round) {
    std::vector<std::uint32_t> changed;
    for (int k = 0; k < 30; ++k) {
      const std::uint32_t v = pick(rng);
      m.vertices[v].z() += 0.05 * (k % 3 - 1) + 0.01 * round;
      for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
        for (const std::uint32_t c : m.triangles[t])
          if (c == v) changed.push_back(t);
    }
    partial.refit(m.vertices, m.triangles, changed);
    full.refit(m.vertices, m.triangles);
    for (std::size_t i = 0; i < full.nodes().size(); ++i) {
      REQUIRE(partial.nodes()[i].box.aabb().lo == full.nodes()[i].box.aabb().lo);
      REQUIRE(partial.nodes()[i].box.aabb().hi == full.nodes()[i].box.aabb().hi);
    }
    // The exact root box too (it shrinks when the outermost vertices move in).
    REQUIRE(partial.box().lo == full.box().lo);
    REQUIRE(partial.box().hi == full.box().hi);
    REQUIRE(full.box().lo == bounds(m).lo);
    REQUIRE(full.box().hi == bounds(m).hi);
  }
}

TEST_CASE("Bvh: a refit in ranges (as the World splits it over threads) equals a whole refit", "[bvh]") {
  Mesh m = make_uv_sphere(Vec3(0, 0, 0), 1.0, 20, 24);
  Bvh split, whole;
  split.build(m.vertices, m.triangles);
  whole.build(m.vertices, m.triangles);
  for (Vec3& v : m.vertices) v = 0.8 * v + Vec3(0.3 * v.y(), 0.1, -0.2 * v.x() * v.x());
  const std::size_t nv = m.vertices.size(), nl = split.leaves();
  Aabb exact;
  for (std::size_t k = 0; k < 3; ++k) {
    const Aabb part = split.refit_vertices(m.vertices, nv * k / 3, nv * (k + 1) / 3);
    exact.extend(part.lo);
    exact.extend(part.hi);
  }
  for (std::size_t k = 0; k < 3; ++k) split.refit_leaves(m.vertices, nl * k / 3, nl * (k + 1) / 3);
  split.refit_nodes(exact);
  whole.refit(m.vertices, m.triangles);
  for (std::size_t i = 0; i < whole.nodes().size(); ++i) {
    REQUIRE(split.nodes()[i].box.aabb().lo == whole.nodes()[i].box.aabb().lo);
    REQUIRE(split.nodes()[i].box.aabb().hi == whole.nodes()[i].box.aabb().hi);
  }
  CHECK(split.box().lo == bounds(m).lo);
  CHECK(split.box().hi == bounds(m).hi);
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t) {  // every triangle's box the new one
    const FBox want = FBox::enclosing(triangle_bounds(m, t)), got = split.triangle_box(t);
    for (int k = 0; k < 3; ++k) REQUIRE((got.lo[k] == want.lo[k] && got.hi[k] == want.hi[k]));
  }
}

TEST_CASE("Bvh: a refit of the nodes by subtrees (plan_parts, refit_part, refit_top) equals a whole refit, whatever the parts", "[bvh]") {
  Mesh m = make_uv_sphere(Vec3(0, 0, 0), 1.0, 30, 34);
  Bvh whole;
  whole.build(m.vertices, m.triangles);
  Mesh moved = m;
  for (Vec3& v : moved.vertices) v = 0.8 * v + Vec3(0.3 * v.y(), 0.1, -0.2 * v.x() * v.x());
  whole.refit(moved.vertices, moved.triangles);
  double growth_of_64 = -1.0;
  for (const std::size_t want : {std::size_t(1), std::size_t(2), std::size_t(7), std::size_t(64), std::size_t(100000)}) {
    CAPTURE(want);
    Bvh split;
    split.build(m.vertices, m.triangles);
    const Aabb exact = split.refit_vertices(moved.vertices, 0, moved.vertices.size());
    const std::size_t parts = split.plan_parts(want);
    REQUIRE(parts >= 1);
    REQUIRE(parts <= std::max<std::size_t>(want, 1));
    if (want > 1) REQUIRE(parts >= std::min(want, split.leaves()) / 2);  // a level at a time: at least half
    split.refit_leaves(moved.vertices, 0, split.leaves());
    for (std::size_t k = parts; k-- > 0;) split.refit_part(k);  // (any order)
    split.refit_top(exact);
    for (std::size_t i = 0; i < whole.nodes().size(); ++i) {
      REQUIRE(split.nodes()[i].box.aabb().lo == whole.nodes()[i].box.aabb().lo);
      REQUIRE(split.nodes()[i].box.aabb().hi == whole.nodes()[i].box.aabb().hi);
    }
    CHECK(split.box().lo == bounds(moved).lo);
    CHECK(split.box().hi == bounds(moved).hi);
    CHECK(split.growth() == Approx(whole.growth()).epsilon(1e-12));
    for (std::uint32_t t = 0; t < moved.triangles.size(); ++t) {
      const FBox want_box = FBox::enclosing(triangle_bounds(moved, t)), got = split.triangle_box(t);
      for (int k = 0; k < 3; ++k) REQUIRE((got.lo[k] == want_box.lo[k] && got.hi[k] == want_box.hi[k]));
    }
    if (want == 64) {  // the same parts give the same sums, bit for bit
      Bvh again;
      again.build(m.vertices, m.triangles);
      const Aabb e = again.refit_vertices(moved.vertices, 0, moved.vertices.size());
      REQUIRE(again.plan_parts(64) == parts);
      again.refit_leaves(moved.vertices, 0, again.leaves());
      for (std::size_t k = 0; k < parts; ++k) again.refit_part(k);
      again.refit_top(e);
      growth_of_64 = split.growth();
      CHECK(again.growth() == growth_of_64);
    }
  }
  CHECK(growth_of_64 > 0.0);  // (set: the check above ran)
}

TEST_CASE("Bvh: a build by subtrees (plan_build, build_part, finish_build) is the whole build, whatever the parts", "[bvh]") {
  // A crumpled cloth (every axis splits somewhere), a small sheet, a one-leaf mesh, a mesh of
  // one leaf and one more triangle, and an empty one.
  const Mesh cloth = make_crumpled_cloth(40, 0.3);
  const auto first_triangles = [](Mesh m, std::size_t n) {
    m.triangles.resize(n);
    return m;
  };
  const Mesh one_leaf = first_triangles(make_crumpled_cloth(2, 0.1), kBvhLeafSize);
  const Mesh nine = first_triangles(make_crumpled_cloth(3, 0.1), kBvhLeafSize + 1);
  const Mesh empty_mesh{make_crumpled_cloth(2, 0.1).vertices, {}};
  const Mesh other = make_uv_sphere(Vec3(0, 0, 0), 1.0, 8, 9);
  for (const Mesh* m : {&cloth, &one_leaf, &nine, &empty_mesh}) {
    Bvh whole;
    whole.build(m->vertices, m->triangles);
    for (const std::size_t want : {std::size_t(0), std::size_t(2), std::size_t(3), std::size_t(8), std::size_t(100000)}) {
      CAPTURE(m->triangles.size(), want);
      Bvh split;
      split.build(other.vertices, other.triangles);  // (a tree to replace)
      const std::size_t parts = split.plan_build(m->vertices, m->triangles, want);
      CHECK(parts <= std::max<std::size_t>(want, 1));
      CHECK((parts == 0) == m->triangles.empty());
      if (want > 1) CHECK(parts >= std::min(want, whole.leaves()) / 2);  // a level at a time: at least half
      for (std::size_t k = parts; k-- > 0;) split.build_part(k);  // (any order)
      split.finish_build(m->triangles);
      REQUIRE(split.nodes().size() == whole.nodes().size());
      REQUIRE(split.leaves() == whole.leaves());
      CHECK(split.depth() == whole.depth());
      CHECK(split.order() == whole.order());
      CHECK(split.growth() == 1.0);
      for (std::uint32_t i = 0; i < whole.nodes().size(); ++i) {
        const BvhNode &a = split.nodes()[i], &b = whole.nodes()[i];
        REQUIRE((a.first == b.first && a.count == b.count && split.parent(i) == whole.parent(i)));
        REQUIRE(a.box.aabb().lo == b.box.aabb().lo);
        REQUIRE(a.box.aabb().hi == b.box.aabb().hi);
      }
      for (std::uint32_t l = 0; l < whole.leaves(); ++l) {
        const BvhLeaf &a = split.leaf_at(l), &b = whole.leaf_at(l);
        REQUIRE(std::memcmp(a.lo, b.lo, sizeof(a.lo)) == 0);
        REQUIRE(std::memcmp(a.hi, b.hi, sizeof(a.hi)) == 0);
        REQUIRE(std::memcmp(a.tri, b.tri, sizeof(a.tri)) == 0);
        REQUIRE(a.bound.aabb().lo == b.bound.aabb().lo);
        REQUIRE(a.bound.aabb().hi == b.bound.aabb().hi);
      }
      for (std::uint32_t t = 0; t < m->triangles.size(); ++t)
        REQUIRE(split.triangle_box(t).aabb().lo == whole.triangle_box(t).aabb().lo);
      if (!m->triangles.empty()) check_wide(split);
      CHECK(split.box().lo == whole.box().lo);
    }
  }
}

TEST_CASE("Bvh: vertices loaded in ranges (checked, rounded, copied: the World's set_vertices) refit as a whole refit does", "[bvh]") {
  // Large enough (past 65,536 vertices) for the streamed stores and the prefetches.
  Mesh m = make_uv_sphere(Vec3(0, 0, 0), 1.0, 200, 400);
  REQUIRE(m.vertices.size() >= 65536);
  Bvh loaded, whole;
  loaded.build(m.vertices, m.triangles);
  whole.build(m.vertices, m.triangles);
  CHECK(loaded.leaves() == (m.triangles.size() + kBvhLeafSize - 1) / kBvhLeafSize);  // full leaves
  for (Vec3& v : m.vertices) v = 0.8 * v + Vec3(0.3 * v.y(), 0.1, -0.2 * v.x() * v.x());
  const std::size_t nv = m.vertices.size(), nl = loaded.leaves();
  std::vector<Vec3> copy(nv, Vec3::Zero());
  {  // a bad vertex stops its range there and is named
    std::vector<Vec3> bad = m.vertices;
    bad[nv / 2 + 7].y() = -INFINITY;
    std::size_t at = 0;
    loaded.load_vertices(bad, copy.data(), nv / 2, nv, at);
    CHECK(at == nv / 2 + 7);
    loaded.load_vertices(bad, copy.data(), 0, nv / 2, at);
    CHECK(at == nv / 2);  // none in this range: its end
  }
  Aabb exact;
  for (std::size_t k = 0; k < 3; ++k) {  // odd and even range starts: the paired stores' edges
    std::size_t at = 0;
    const std::size_t begin = nv * k / 3 + (k == 1), end = k == 2 ? nv : nv * (k + 1) / 3 + 1;
    const Aabb part = loaded.load_vertices(m.vertices, copy.data(), begin, end, at);
    CHECK(at == end);
    exact.extend(part.lo);
    exact.extend(part.hi);
  }
  CHECK(copy == m.vertices);  // every vertex copied, bit for bit
  for (std::size_t k = 0; k < 2; ++k) loaded.refit_leaves(m.vertices, nl * k / 2, nl * (k + 1) / 2);
  loaded.refit_nodes(exact);
  whole.refit(m.vertices, m.triangles);
  for (std::size_t i = 0; i < whole.nodes().size(); ++i) {
    REQUIRE(loaded.nodes()[i].box.aabb().lo == whole.nodes()[i].box.aabb().lo);
    REQUIRE(loaded.nodes()[i].box.aabb().hi == whole.nodes()[i].box.aabb().hi);
  }
  CHECK(loaded.box().lo == bounds(m).lo);
  CHECK(loaded.box().hi == bounds(m).hi);
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t) {
    const FBox want = FBox::enclosing(triangle_bounds(m, t)), got = loaded.triangle_box(t);
    for (int k = 0; k < 3; ++k) REQUIRE((got.lo[k] == want.lo[k] && got.hi[k] == want.hi[k]));
  }
}

TEST_CASE("Bvh: vertices loaded without rounding are checked, copied and boxed, and refit from refit_vertices() as a whole refit does", "[bvh]") {
  Mesh m = make_uv_sphere(Vec3(0, 0, 0), 1.0, 200, 400);  // past 65,536 vertices: the streamed stores
  Bvh loaded, whole;
  loaded.build(m.vertices, m.triangles);
  whole.build(m.vertices, m.triangles);
  for (Vec3& v : m.vertices) v = 0.7 * v + Vec3(0.2 * v.z(), -0.1, 0.3 * v.y() * v.y());
  const std::size_t nv = m.vertices.size();
  std::vector<Vec3> copy(nv, Vec3::Zero());
  std::size_t at = 0;
  std::vector<Vec3> bad = m.vertices;
  bad[nv / 3].x() = NAN;
  loaded.load_vertices(bad, copy.data(), 0, nv, at, /*round=*/false);
  CHECK(at == nv / 3);
  const Aabb box = loaded.load_vertices(m.vertices, copy.data(), 0, nv, at, /*round=*/false);
  CHECK(at == nv);
  CHECK(copy == m.vertices);
  CHECK(box.lo == bounds(m).lo);
  CHECK(box.hi == bounds(m).hi);
  // Unrounded: a refit from the vertex boxes alone would not see the new vertices.
  loaded.refit_leaves(m.vertices, 0, loaded.leaves());
  const FBox stale = loaded.triangle_box(0), fresh = FBox::enclosing(triangle_bounds(m, 0));
  bool same = true;
  for (int k = 0; k < 3; ++k) same = same && stale.lo[k] == fresh.lo[k] && stale.hi[k] == fresh.hi[k];
  CHECK_FALSE(same);
  const Aabb exact = loaded.refit_vertices(m.vertices, 0, nv);
  loaded.refit_leaves(m.vertices, 0, loaded.leaves());
  loaded.refit_nodes(exact);
  whole.refit(m.vertices, m.triangles);
  for (std::size_t i = 0; i < whole.nodes().size(); ++i) {
    REQUIRE(loaded.nodes()[i].box.aabb().lo == whole.nodes()[i].box.aabb().lo);
    REQUIRE(loaded.nodes()[i].box.aabb().hi == whole.nodes()[i].box.aabb().hi);
  }
}

TEST_CASE("Bvh: a refit rounds every corner outward at every scale, as a build does", "[bvh]") {
  // A grid whose vertices are scaled through subnormals, float's limit and past it (infinite
  // float boxes), so that the refit's vector path and its scalar fallback both run.
  Mesh m = make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 12, 12);
  const double scales[] = {1e-44, 1e-39, 0.37, 3.3e36, 1e37, 2.9e38, 3.5e38, 1e300};
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    const double s = scales[v % 8];
    m.vertices[v] = Vec3(s * m.vertices[v].x() + 0.1 * s, -s * m.vertices[v].y(), s * (v % 3 == 0 ? -1.0 : 1.0) / 3.0);
  }
  Bvh built, refitted;
  built.build(m.vertices, m.triangles);
  const Mesh first = make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 12, 12);
  refitted.build(first.vertices, first.triangles);
  refitted.refit(m.vertices, m.triangles);
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t) {
    const Aabb exact = triangle_bounds(m, t);
    const FBox want = FBox::enclosing(exact), got = refitted.triangle_box(t);
    for (int k = 0; k < 3; ++k) {
      REQUIRE((double(got.lo[k]) <= exact.lo[k] && double(got.hi[k]) >= exact.hi[k]));
      REQUIRE((got.lo[k] == want.lo[k] && got.hi[k] == want.hi[k]));
      REQUIRE((got.lo[k] == built.triangle_box(t).lo[k] && got.hi[k] == built.triangle_box(t).hi[k]));
    }
  }
  CHECK(refitted.box().lo == bounds(m).lo);
  CHECK(refitted.box().hi == bounds(m).hi);
}

TEST_CASE("Bvh: the traversal of two posed trees finds every couple of overlapping boxes", "[bvh]") {
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 16);
  const Mesh b = make_box(Vec3(-0.4, -0.4, -0.4), Vec3(0.4, 0.4, 0.4));
  const Mesh grid = make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 9, 9);
  Bvh ta, tb, tg;
  ta.build(a.vertices, a.triangles);
  tb.build(b.vertices, b.triangles);
  tg.build(grid.vertices, grid.triangles);
  std::vector<BvhStackEntry> stack;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Affine3d pa = pose(0.3 * k, Vec3(1, 2, 3), Vec3(0.1 * k, 0, 0));
    const Eigen::Affine3d pb = pose(-0.5 * k, Vec3(0, 1, 1), Vec3(0.9, 0.05 * k, 0.2));
    for (const auto& [mesh, tree] : {std::pair<const Mesh*, const Bvh*>{&b, &tb}, {&grid, &tg}}) {
      const BvhRelation rel = BvhRelation::between(pa, pb);
      std::set<std::pair<std::uint32_t, std::uint32_t>> got;
      bvh_traverse(ta, *tree, rel, BvhNodePair{0u, 0u}, stack,
                   [&](std::uint32_t x, std::uint32_t y) { REQUIRE(got.emplace(x, y).second); });
      const auto want = scan(a, pa, *mesh, pb);
      // Every couple whose boxes overlap in both frames; boxes carried through the pose (a box of
      // a box) may add some.
      REQUIRE(std::includes(got.begin(), got.end(), want.begin(), want.end()));
      CHECK(got.size() <= 4 * want.size() + 64);
      // The boxes carried in floats (the path taken here) or in doubles: both find them.
      REQUIRE(rel.float_ok);
      std::set<std::pair<std::uint32_t, std::uint32_t>> in_doubles;
      const bvh_detail::Posed<bvh_detail::DoubleCarry> doubles{ta, *tree, rel, {rel}};
      auto add = [&](std::uint32_t x, std::uint32_t y) { REQUIRE(in_doubles.emplace(x, y).second); };
      bvh_detail::traverse_pairs(doubles, ta, *tree, BvhNodePair{0u, 0u}, stack, add);
      REQUIRE(std::includes(in_doubles.begin(), in_doubles.end(), want.begin(), want.end()));
      CHECK(in_doubles.size() <= 4 * want.size() + 64);
      // Split into tasks: the same couples, each once.
      std::vector<BvhNodePair> tasks;
      bvh_split(ta, *tree, rel, 6, tasks);
      std::set<std::pair<std::uint32_t, std::uint32_t>> split;
      for (const BvhNodePair& start : tasks)
        bvh_traverse(ta, *tree, rel, start, stack,
                     [&](std::uint32_t x, std::uint32_t y) { REQUIRE(split.emplace(x, y).second); });
      CHECK(split == got);
    }
  }
}

TEST_CASE("Bvh: a box carried through a pose in floats encloses its image, at every scale", "[bvh]") {
  // Boxes from 1e-30 to 1e25 across, near and far from the origin, through rotations, scales
  // and shears; the carried box against the eight corners' images in long double (through the
  // relation's double maps, whose own rounding is far below the float bound), and not much
  // larger than their box.
  std::mt19937_64 rng(58);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 25);
  std::size_t carried = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::Affine3d pa = pose(3.0 * unit(rng), Vec3(unit(rng), unit(rng), 1.0), Vec3(unit(rng), unit(rng), unit(rng)) * std::pow(10.0, exponent(rng) / 3));
    Eigen::Affine3d pb = pose(3.0 * unit(rng), Vec3(1.0, unit(rng), unit(rng)), Vec3(unit(rng), unit(rng), unit(rng)) * std::pow(10.0, exponent(rng) / 3));
    if (trial % 3 == 1) pb.linear() *= std::pow(10.0, unit(rng) * 3.0);  // a scale
    if (trial % 3 == 2) pa.linear()(0, 1) += 2.0 * unit(rng);           // a shear
    const BvhRelation rel = BvhRelation::between(pa, pb);
    REQUIRE(rel.float_ok);
    const bvh_detail::FloatCarry carry{rel.float_to_a, rel.float_to_b};
    for (int k = 0; k < 8; ++k) {
      const double size = std::pow(10.0, exponent(rng)), offset = std::pow(10.0, exponent(rng));
      Aabb box;
      for (int c = 0; c < 2; ++c) box.extend(Vec3(unit(rng), unit(rng), unit(rng)) * size + Vec3::Constant(offset * unit(rng)));
      const FBox fb = FBox::enclosing(box);
      for (const bool into_b : {false, true}) {
        const FBox got = into_b ? carry.to_b(fb) : carry.to_a(fb);
        const Eigen::Matrix3d& l = into_b ? rel.inv_linear : rel.linear;
        const Vec3& t = into_b ? rel.inv_translation : rel.translation;
        long double lo[3], hi[3], mag[3];
        for (int d = 0; d < 3; ++d) lo[d] = INFINITY, hi[d] = -INFINITY, mag[d] = std::abs((long double)t[d]);
        for (int corner = 0; corner < 8; ++corner) {
          const double p[3] = {corner & 1 ? fb.hi[0] : fb.lo[0], corner & 2 ? fb.hi[1] : fb.lo[1], corner & 4 ? fb.hi[2] : fb.lo[2]};
          for (int d = 0; d < 3; ++d) {
            long double v = t[d];
            for (int j = 0; j < 3; ++j) v += (long double)l(d, j) * p[j];
            lo[d] = std::min(lo[d], v), hi[d] = std::max(hi[d], v);
          }
        }
        for (int d = 0; d < 3; ++d) {
          for (int j = 0; j < 3; ++j)
            mag[d] += std::abs((long double)l(d, j)) * std::max(std::abs(fb.lo[j]), std::abs(fb.hi[j]));
          REQUIRE(got.lo[d] <= lo[d]);
          REQUIRE(got.hi[d] >= hi[d]);
          // Grown by at most 2^-19 of the magnitudes, the relation's fixed growth and the float
          // roundings (a few more 2^-24).
          const long double slack = mag[d] * 0x1p-18L + 2.0L * rel.float_to_a.grow + 2.0L * rel.float_to_b.grow;
          REQUIRE(got.hi[d] - hi[d] <= slack);
          REQUIRE(lo[d] - got.lo[d] <= slack);
        }
        ++carried;
      }
    }
  }
  CHECK(carried == 400 * 8 * 2);
  // A leaf's lanes carried together equal each lane carried alone, bit for bit; lanes outside
  // the mask (empty ones among them: infinities) are skipped.
  std::size_t lanes_checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Affine3d pb = pose(3.0 * unit(rng), Vec3(1.0, unit(rng), unit(rng)), Vec3(unit(rng), unit(rng), unit(rng)) * 10.0);
    if (trial % 2) pb.linear() *= 3.7;
    const BvhRelation rel = BvhRelation::between(pose(unit(rng), Vec3(0, 0, 1), Vec3::Zero()), pb);
    const bvh_detail::FloatCarry carry{rel.float_to_a, rel.float_to_b};
    const double scale = std::pow(10.0, exponent(rng) / 2);
    BvhLeaf leaf;
    const std::uint32_t count = 1 + std::uint32_t(trial % kBvhLeafSize);
    for (std::uint32_t u = 0; u < kBvhLeafSize; ++u) {
      Aabb box;
      for (int c = 0; c < 2; ++c) box.extend(Vec3(unit(rng), unit(rng), unit(rng)) * scale);
      leaf.set(u, u < count ? FBox::enclosing(box) : FBox{});
      leaf.tri[u] = u;
    }
    const unsigned lanes = ((1u << count) - 1u) & unsigned(rng());
    BvhLeaf together, in_doubles;
    carry.leaf_to_b(leaf, lanes, together);
    bvh_detail::DoubleCarry{rel}.leaf_to_b(leaf, lanes, in_doubles);
    for (std::uint32_t u = 0; u < count; ++u) {
      if (!((lanes >> u) & 1u)) continue;
      const FBox alone = carry.to_b(leaf.box(u)), d = bvh_detail::DoubleCarry{rel}.to_b(leaf.box(u));
      for (int k = 0; k < 3; ++k) {
#if !defined(__FMA__)  // (a build that may fuse products and sums could fuse the two differently)
        REQUIRE(std::memcmp(&together.lo[k][u], &alone.lo[k], sizeof(float)) == 0);
        REQUIRE(std::memcmp(&together.hi[k][u], &alone.hi[k], sizeof(float)) == 0);
#else
        REQUIRE(std::abs(together.lo[k][u] - alone.lo[k]) <= 1e-5f * (std::abs(alone.lo[k]) + std::abs(alone.hi[k])));
        REQUIRE(std::abs(together.hi[k][u] - alone.hi[k]) <= 1e-5f * (std::abs(alone.lo[k]) + std::abs(alone.hi[k])));
#endif
        REQUIRE((in_doubles.lo[k][u] == d.lo[k] && in_doubles.hi[k][u] == d.hi[k]));
      }
      ++lanes_checked;
    }
  }
  CHECK(lanes_checked > 300);
  // Out of the floats' range, the traversal carries in doubles.
  Eigen::Affine3d big = Eigen::Affine3d::Identity();
  big.linear() *= 2e6;
  CHECK_FALSE(BvhRelation::between(Eigen::Affine3d::Identity(), big).float_ok);
  CHECK_FALSE(BvhRelation::between(Eigen::Affine3d::Identity(), Eigen::Affine3d(Eigen::Translation3d(1e31, 0, 0))).float_ok);
}

TEST_CASE("Bvh: the self traversal gives every couple of distinct triangles whose boxes overlap, once", "[bvh]") {
  const Mesh m = make_folded_sheet(12, 0.3, 0.2);
  Bvh t;
  t.build(m.vertices, m.triangles);
  std::vector<BvhNodePair> stack;
  std::set<std::pair<std::uint32_t, std::uint32_t>> got;
  bvh_self_traverse(t, stack, [&](std::uint32_t x, std::uint32_t y) {
    REQUIRE(x != y);
    REQUIRE(got.emplace(std::min(x, y), std::max(x, y)).second);
  });
  std::set<std::pair<std::uint32_t, std::uint32_t>> want;
  for (std::uint32_t x = 0; x < m.triangles.size(); ++x)
    for (std::uint32_t y = x + 1; y < m.triangles.size(); ++y)
      if (triangle_bounds(m, x).overlaps(triangle_bounds(m, y))) want.emplace(x, y);
  REQUIRE(std::includes(got.begin(), got.end(), want.begin(), want.end()));
  for (const auto& [x, y] : got) {  // any other couple: within float rounding of touching
    Aabb grown = triangle_bounds(m, x);
    grown.lo -= Vec3::Constant(1e-6);
    grown.hi += Vec3::Constant(1e-6);
    REQUIRE(grown.overlaps(triangle_bounds(m, y)));
  }
}

TEST_CASE("Bvh: the self traversal without adjacent couples drops exactly those sharing a corner", "[bvh][self]") {
  // bvh_self_traverse_apart() against bvh_self_traverse() and triangles_adjacent(): by index
  // (rep null) and by position (a soup whose triangles share no index, welded by their
  // representatives), on a folded sheet, a crumpled cloth and the soup of the crumpled cloth.
  std::vector<Mesh> meshes{make_folded_sheet(12, 0.3, 0.2), make_crumpled_cloth(10, 0.4)};
  Mesh soup;  // every triangle its own three vertices
  for (const Tri& f : meshes[1].triangles) {
    const std::uint32_t base = std::uint32_t(soup.vertices.size());
    for (int k = 0; k < 3; ++k) soup.vertices.push_back(meshes[1].vertices[f[k]]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  meshes.push_back(soup);
  for (std::size_t i = 0; i < meshes.size(); ++i)
    for (const SelfAdjacency adjacency : {SelfAdjacency::index, SelfAdjacency::position}) {
      INFO("mesh " << i << ", adjacency " << int(adjacency));
      const Mesh& m = meshes[i];
      std::vector<std::uint32_t> reps;
      vertex_representatives(m, adjacency, reps);
      const std::uint32_t* rep = adjacency == SelfAdjacency::index ? nullptr : reps.data();
      Bvh t;
      t.build(m.vertices, m.triangles);
      std::vector<BvhNodePair> stack;
      std::set<std::pair<std::uint32_t, std::uint32_t>> want, got;
      std::size_t adjacent = 0;
      bvh_self_traverse(t, stack, [&](std::uint32_t x, std::uint32_t y) {
        if (triangles_adjacent(m, rep, x, y))
          ++adjacent;
        else
          want.emplace(std::min(x, y), std::max(x, y));
      });
      bvh_self_traverse_apart(t, rep, stack, [&](std::uint32_t x, std::uint32_t y) {
        REQUIRE(got.emplace(std::min(x, y), std::max(x, y)).second);
      });
      CHECK((adjacent > 0) == (i != 2 || adjacency == SelfAdjacency::position));  // the soup shares no index
      CHECK(!want.empty());
      CHECK(got == want);
    }
}

TEST_CASE("Bvh: the self traversal split into node pairs (bvh_self_split) gives the whole traversal's couples, each once", "[bvh][self]") {
  const Mesh m = make_crumpled_cloth(24, 0.4);
  Bvh t;
  t.build(m.vertices, m.triangles);
  std::vector<BvhNodePair> stack;
  std::set<std::pair<std::uint32_t, std::uint32_t>> want;
  bvh_self_traverse_apart(t, nullptr, stack, [&](std::uint32_t x, std::uint32_t y) {
    want.emplace(std::min(x, y), std::max(x, y));
  });
  REQUIRE(want.size() > 100);
  BvhSplitScratch scratch;
  for (const std::size_t tasks : {std::size_t(1), std::size_t(2), std::size_t(16), std::size_t(64), std::size_t(100000)}) {
    CAPTURE(tasks);
    std::vector<BvhNodePair> split;
    bvh_self_split(t, tasks, split, scratch);
    REQUIRE(!split.empty());
    if (tasks > 1) CHECK(split.size() >= std::min<std::size_t>(tasks, 64) / 4);
    std::set<std::pair<std::uint32_t, std::uint32_t>> got;
    for (const BvhNodePair& start : split) {
      CHECK(start.first <= start.second);
      bvh_self_traverse_apart(t, nullptr, start, stack, [&](std::uint32_t x, std::uint32_t y) {
        REQUIRE(got.emplace(std::min(x, y), std::max(x, y)).second);  // once
      });
    }
    CHECK(got == want);
  }
}

TEST_CASE("Bvh: two trees in one frame, traversed on float boxes, give every couple of overlapping boxes", "[bvh]") {
  // bvh_traverse_same_frame() (the World's pairs of world-space trees) against the scan and
  // against the posed traversal at identity poses, from the roots and split into tasks.
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 16);
  const Mesh grid = make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 9, 9);
  Bvh ta, tg;
  ta.build(a.vertices, a.triangles);
  tg.build(grid.vertices, grid.triangles);
  const Eigen::Affine3d id = Eigen::Affine3d::Identity();
  const BvhRelation rel = BvhRelation::between(id, id);
  REQUIRE(rel.identity);
  std::vector<BvhNodePair> stack;
  std::vector<BvhStackEntry> posed_stack;
  std::set<std::pair<std::uint32_t, std::uint32_t>> got, posed;
  bvh_traverse_same_frame(ta, tg, BvhNodePair{0u, 0u}, stack,
                          [&](std::uint32_t x, std::uint32_t y) { REQUIRE(got.emplace(x, y).second); });
  bvh_traverse(ta, tg, rel, BvhNodePair{0u, 0u}, posed_stack, [&](std::uint32_t x, std::uint32_t y) { posed.emplace(x, y); });
  const auto want = scan(a, id, grid, id);
  CHECK(got == want);
  CHECK(posed == want);
  CHECK_FALSE(want.empty());
  std::vector<BvhNodePair> tasks;
  bvh_split(ta, tg, rel, 6, tasks);
  std::set<std::pair<std::uint32_t, std::uint32_t>> split;
  for (const BvhNodePair& start : tasks)
    bvh_traverse_same_frame(ta, tg, start, stack, [&](std::uint32_t x, std::uint32_t y) { REQUIRE(split.emplace(x, y).second); });
  CHECK(split == want);
}

TEST_CASE("Bvh: the wide traversal of two trees in one frame gives the binary traversal's couples", "[bvh]") {
  // bvh_traverse_same_frame() walks the trees' wide views; the binary kernel (bvh_detail::SameFrame)
  // on the same trees, from every start a split gives (odd-depth nodes, leaves and wide nodes),
  // over meshes of many sizes against each other, moved into contact, some refitted.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> d(-0.05, 0.05);
  std::vector<Mesh> meshes;
  for (const int n : {1, 2, 3, 5, 8, 13, 21})
    meshes.push_back(make_uv_sphere(Vec3(0.1 * n, 0, 0), 1.0, 3 + n, 4 + n));
  meshes.push_back(make_grid(Vec3(-1, -1, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 1, 1));
  meshes.push_back(make_grid(Vec3(-1, -1, 0.2), Vec3(2, 0, 0), Vec3(0, 2, 0), 30, 17));
  meshes.push_back(make_box(Vec3(-0.3, -0.3, -0.3), Vec3(0.4, 0.4, 0.4)));
  std::vector<Bvh> trees(meshes.size());
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    if (i % 3 == 1) {  // a refitted tree: its boxes loosened, its wide view synced
      Mesh m = meshes[i];
      trees[i].build(m.vertices, m.triangles);
      for (Vec3& v : meshes[i].vertices) v += Vec3(d(rng), d(rng), d(rng));
      trees[i].refit(meshes[i].vertices, meshes[i].triangles);
      REQUIRE_FALSE(trees[i].wide_fresh());
      trees[i].sync_wide();
    } else {
      trees[i].build(meshes[i].vertices, meshes[i].triangles);
    }
  }
  const BvhRelation rel{};  // identity
  std::vector<BvhNodePair> stack, tasks;
  std::size_t couples = 0;
  for (std::size_t i = 0; i < meshes.size(); ++i)
    for (std::size_t j = 0; j < meshes.size(); ++j) {
      using Set = std::set<std::pair<std::uint32_t, std::uint32_t>>;
      Set wide, binary;
      REQUIRE((trees[i].wide_fresh() && trees[j].wide_fresh()));  // bvh_traverse_same_frame() goes wide
      bvh_traverse_same_frame(trees[i], trees[j], BvhNodePair{0u, 0u}, stack,
                              [&](std::uint32_t x, std::uint32_t y) { REQUIRE(wide.emplace(x, y).second); });
      const bvh_detail::SameFrame frame{trees[i], trees[j]};
      auto add = [&](std::uint32_t x, std::uint32_t y) { REQUIRE(binary.emplace(x, y).second); };
      bvh_detail::traverse_pairs(frame, trees[i], trees[j], BvhNodePair{0u, 0u}, stack, add);
      REQUIRE(wide == binary);
      couples += wide.size();
      for (const std::size_t n : {2u, 5u, 13u}) {
        bvh_split(trees[i], trees[j], rel, n, tasks);
        Set split;
        for (const BvhNodePair& start : tasks)
          bvh_traverse_same_frame(trees[i], trees[j], start, stack,
                                  [&](std::uint32_t x, std::uint32_t y) { REQUIRE(split.emplace(x, y).second); });
        REQUIRE(split == binary);
      }
    }
  CHECK(couples > 1000);
}

TEST_CASE("Bvh: a CoupleKeys sink keeps the couples a plain visitor gets, in its order", "[bvh]") {
  // The World's candidates come through bvh_detail::CoupleKeys (a leaf lane's couples written
  // at once, buffered): the same keys in the same order as fn(a, b) one by one, on the wide
  // traversal in one frame and on the posed one, over many more couples than its buffer holds.
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 40, 48);
  const Mesh b = make_uv_sphere(Vec3(0.3, 0.1, 0), 1.0, 37, 45);
  Bvh ta, tb;
  ta.build(a.vertices, a.triangles);
  tb.build(b.vertices, b.triangles);
  std::vector<BvhNodePair> stack;
  std::vector<BvhStackEntry> posed_stack;
  std::vector<std::uint64_t> plain, keys = {pack_pair(7, 9)};  // a sink appends to what is there
  const auto push = [&](std::uint32_t x, std::uint32_t y) { plain.push_back(pack_pair(x, y)); };
  plain.push_back(pack_pair(7, 9));
  bvh_traverse_same_frame(ta, tb, BvhNodePair{0u, 0u}, stack, push);
  {
    bvh_detail::CoupleKeys sink(keys);
    bvh_traverse_same_frame(ta, tb, BvhNodePair{0u, 0u}, stack, sink);
    sink.finish();
  }
  CHECK(plain.size() > 2000);
  CHECK(keys == plain);
  const BvhRelation rel = BvhRelation::between(pose(0.4, Vec3(1, 2, 3), Vec3(0.1, 0, 0)), pose(-0.2, Vec3(0, 1, 1), Vec3(0.2, 0.1, 0)));
  plain.clear();
  keys.clear();
  bvh_traverse(ta, tb, rel, BvhNodePair{0u, 0u}, posed_stack, push);
  {
    bvh_detail::CoupleKeys sink(keys);
    bvh_traverse(ta, tb, rel, BvhNodePair{0u, 0u}, posed_stack, sink);
    sink.finish();
  }
  CHECK(plain.size() > 500);
  CHECK(keys == plain);
}

TEST_CASE("Bvh: a vertex no triangle uses stays out of the box, built and refitted", "[bvh]") {
  Mesh m = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Aabb corners = [&] {
    Aabb b;
    for (const Tri& f : m.triangles)
      for (const std::uint32_t v : f) b.extend(m.vertices[v]);
    return b;
  }();
  m.vertices.push_back(Vec3(50, -50, 9));  // used by no triangle
  Bvh t;
  t.build(m.vertices, m.triangles);
  CHECK(t.box().lo == corners.lo);
  CHECK(t.box().hi == corners.hi);
  for (Vec3& v : m.vertices) v += Vec3(0.5, 0.25, -1);
  t.refit(m.vertices, m.triangles);
  CHECK(t.box().lo == corners.lo + Vec3(0.5, 0.25, -1));
  CHECK(t.box().hi == corners.hi + Vec3(0.5, 0.25, -1));
}
