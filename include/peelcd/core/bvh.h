#pragma once
// A bounding volume hierarchy over a mesh's triangles, kept across frames: built once in the
// object's own frame (a rigid object's shape space; a deforming object's world space), refitted
// when vertices move (all of it, or only the leaves holding changed triangles and their
// ancestors), rebuilt when the topology changes. peelcd::World keeps one per body.
//
// Binary, nodes in depth-first order (a node's left child follows it; its parent comes before
// it), leaves of at most kBvhLeafSize triangles, split at the median centroid along the longest
// axis of the centroids' box. Boxes are closed and exact: the min/max of the corners' doubles.
#include "peelcd/core/aabb.h"

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace peelcd {

constexpr std::uint32_t kBvhLeafSize = 4;

struct BvhNode {
  Aabb box;
  std::uint32_t first = 0;   // leaf: first index into Bvh::order(); internal: the right child
  std::uint32_t count = 0;   // leaf: triangles (>= 1); internal: 0
  std::uint32_t parent = 0;  // the root's is itself (0)
  bool leaf() const { return count != 0; }
};

class Bvh {
 public:
  // Builds over `triangles` of `vertices` (indices checked by the caller: validate_mesh).
  void build(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);
  // Every box again from `vertices` (the same triangles, moved).
  void refit(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);
  // Only the boxes of `changed` triangles (any order, repeats allowed), their leaves and their
  // ancestors: O(changed * depth).
  void refit(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles,
             const std::vector<std::uint32_t>& changed);

  bool empty() const { return nodes_.empty(); }
  std::size_t triangles() const { return boxes_.size(); }
  // The root's box (empty() for an empty tree).
  Aabb box() const { return nodes_.empty() ? Aabb{} : nodes_[0].box; }
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  const std::vector<std::uint32_t>& order() const { return order_; }  // triangles, leaf by leaf
  const Aabb& triangle_box(std::uint32_t t) const { return boxes_[t]; }
  std::size_t depth() const { return depth_; }

  // The triangles whose boxes touch `box` (closed, in the tree's frame), ascending, into `out`.
  void query(const Aabb& box, std::vector<std::uint32_t>& out) const;

 private:
  std::uint32_t build_node(std::uint32_t begin, std::uint32_t end, std::uint32_t parent, std::size_t level,
                           std::vector<Vec3>& centroids);
  void refit_node(std::uint32_t n);
  std::vector<BvhNode> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<std::uint32_t> leaf_of_;  // triangle -> its leaf node
  std::vector<Aabb> boxes_;             // triangle -> its box
  std::vector<std::uint8_t> dirty_;     // scratch of the partial refit, per node
  std::vector<std::uint32_t> stack_;    // scratch of the partial refit
  std::size_t depth_ = 0;
};

// B's frame into A's, for the traversal of two trees: p_a = linear * p_b + translation. With
// `identity` (both in world space, e.g. two deforming bodies) boxes are compared as they are.
struct BvhRelation {
  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d abs_linear = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  // A's frame into B's (the inverse).
  Eigen::Matrix3d inv_linear = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d inv_abs_linear = Eigen::Matrix3d::Identity();
  Vec3 inv_translation = Vec3::Zero();
  bool identity = true;
  // The magnitude of the poses' translations: world coordinates carry rounding of that size,
  // which the grown boxes must cover too.
  double reach = 0.0;

  // B's box as seen from A: the box enclosing its image, grown by 1e-9 of the magnitudes
  // involved (the box's, and the poses' translations: `reach`) so that the rounding of the
  // transforms, here and in the world coordinates the exact test reads, never drops a pair whose
  // world-space triangles touch.
  Aabb to_a(const Aabb& b) const { return identity ? b : moved(b, linear, abs_linear, translation, reach); }
  // A's box as seen from B, the same way.
  Aabb to_b(const Aabb& a) const { return identity ? a : moved(a, inv_linear, inv_abs_linear, inv_translation, reach); }
  // A's box `a` and B's box `b` (whose image in A's frame is `b_in_a`) may overlap: tested in
  // both frames (a separating axis among A's three or B's three).
  bool overlap(const Aabb& a, const Aabb& b_in_a, const Aabb& b) const {
    return a.overlaps(b_in_a) && (identity || to_b(a).overlaps(b));
  }
  static BvhRelation between(const Eigen::Affine3d& pose_a, const Eigen::Affine3d& pose_b);
  static Aabb moved(const Aabb& box, const Eigen::Matrix3d& linear, const Eigen::Matrix3d& abs_linear,
                    const Vec3& translation, double reach);
};

// A pair of nodes (A's, B's) still to visit.
using BvhNodePair = std::pair<std::uint32_t, std::uint32_t>;

// A node pair on the traversal's stack, with B's box as seen from A (computed once, when the
// pair is pushed; descending into A's children keeps it).
struct BvhStackEntry {
  std::uint32_t a, b;
  Aabb b_in_a;
};

// Splits the traversal of (a, b) into at least `tasks` independent node pairs where the trees
// allow (breadth first from the roots; leaf pairs and disjoint pairs settled on the way: the
// disjoint dropped, the leaf pairs appended to `tasks_out` like any other).
void bvh_split(const Bvh& a, const Bvh& b, const BvhRelation& rel, std::size_t tasks,
               std::vector<BvhNodePair>& tasks_out);

// Every couple (triangle of a, triangle of b) under the node pair `start` whose boxes overlap (B's
// through `rel`): fn(tri_a, tri_b). `stack` is scratch. Returns the node pairs visited.
template <class Fn>
std::size_t bvh_traverse(const Bvh& a, const Bvh& b, const BvhRelation& rel, BvhNodePair start,
                         std::vector<BvhStackEntry>& stack, Fn&& fn) {
  const auto& na = a.nodes();
  const auto& nb = b.nodes();
  std::size_t visited = 0;
  stack.clear();
  {
    const Aabb yb = rel.to_a(nb[start.second].box);
    if (!rel.overlap(na[start.first].box, yb, nb[start.second].box)) return 1;
    stack.push_back({start.first, start.second, yb});
  }
  Aabb leaf_boxes[kBvhLeafSize];
  while (!stack.empty()) {
    const BvhStackEntry e = stack.back();
    stack.pop_back();
    ++visited;
    const BvhNode& x = na[e.a];
    const BvhNode& y = nb[e.b];
    // Invariant: x.box overlaps e.b_in_a (tested before the push).
    if (x.leaf() && y.leaf()) {
      for (std::uint32_t v = 0; v < y.count; ++v) leaf_boxes[v] = rel.to_a(b.triangle_box(b.order()[y.first + v]));
      for (std::uint32_t u = x.first; u < x.first + x.count; ++u) {
        const std::uint32_t ta = a.order()[u];
        const Aabb& ba = a.triangle_box(ta);
        if (!ba.overlaps(e.b_in_a)) continue;
        const Aabb a_in_b = rel.identity ? ba : rel.to_b(ba);
        for (std::uint32_t v = 0; v < y.count; ++v) {
          const std::uint32_t tb = b.order()[y.first + v];
          if (ba.overlaps(leaf_boxes[v]) && a_in_b.overlaps(b.triangle_box(tb))) fn(ta, tb);
        }
      }
    } else if (y.leaf() || (!x.leaf() && x.box.extent().maxCoeff() >= e.b_in_a.extent().maxCoeff())) {
      for (const std::uint32_t c : {e.a + 1, x.first})
        if (rel.overlap(na[c].box, e.b_in_a, y.box)) stack.push_back({c, e.b, e.b_in_a});
    } else {
      for (const std::uint32_t c : {e.b + 1, y.first}) {
        const Aabb yb = rel.to_a(nb[c].box);
        if (rel.overlap(x.box, yb, nb[c].box)) stack.push_back({e.a, c, yb});
      }
    }
  }
  return visited;
}

// Every couple of distinct triangles of one tree whose boxes overlap (closed): fn(t, u), once
// per couple, in no particular order of t and u (the self-collision search: the caller drops
// adjacent couples). `stack` is scratch. Returns the node pairs visited.
template <class Fn>
std::size_t bvh_self_traverse(const Bvh& tree, std::vector<BvhNodePair>& stack, Fn&& fn) {
  const auto& n = tree.nodes();
  if (n.empty()) return 0;
  std::size_t visited = 0;
  stack.clear();
  stack.push_back({0u, 0u});
  const auto leaf_pairs = [&](const BvhNode& x, const BvhNode& y) {
    for (std::uint32_t i = x.first; i < x.first + x.count; ++i) {
      const std::uint32_t t = tree.order()[i];
      const Aabb& bt = tree.triangle_box(t);
      for (std::uint32_t j = y.first; j < y.first + y.count; ++j) {
        const std::uint32_t u = tree.order()[j];
        if (bt.overlaps(tree.triangle_box(u))) fn(t, u);
      }
    }
  };
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    ++visited;
    const BvhNode& x = n[a];
    const BvhNode& y = n[b];
    if (a == b) {  // a node against itself: its children each against itself and each other
      if (x.leaf()) {
        for (std::uint32_t i = x.first; i < x.first + x.count; ++i)
          for (std::uint32_t j = i + 1; j < x.first + x.count; ++j) {
            const std::uint32_t t = tree.order()[i], u = tree.order()[j];
            if (tree.triangle_box(t).overlaps(tree.triangle_box(u))) fn(t, u);
          }
        continue;
      }
      const std::uint32_t l = a + 1, r = x.first;
      stack.push_back({l, l});
      stack.push_back({r, r});
      if (n[l].box.overlaps(n[r].box)) stack.push_back({l, r});
      continue;
    }
    if (x.leaf() && y.leaf()) {
      leaf_pairs(x, y);
    } else if (y.leaf() || (!x.leaf() && x.box.extent().maxCoeff() >= y.box.extent().maxCoeff())) {
      for (const std::uint32_t c : {a + 1, x.first})
        if (n[c].box.overlaps(y.box)) stack.push_back({c, b});
    } else {
      for (const std::uint32_t c : {b + 1, y.first})
        if (x.box.overlaps(n[c].box)) stack.push_back({a, c});
    }
  }
  return visited;
}

}  // namespace peelcd
