#pragma once
// A bounding volume hierarchy over a mesh's triangles, kept across frames: built once in the
// object's own frame (a rigid object's shape space; a deforming object's world space), refitted
// when vertices move (all of it, or only the leaves holding changed triangles and their
// ancestors), rebuilt when the topology changes. peelcd::World keeps one per body.
//
// Binary, nodes in depth-first order (a node's left child follows it; its parent comes before
// it), leaves of kBvhLeafSize triangles (all but one full), split along the longest axis of the
// centroids' box where the left child gets half of the leaves the node needs (the median
// centroid, rounded to whole leaves). Boxes are float, rounded outward from the corners' doubles
// (FBox): half the memory of double boxes, and never smaller than the exact box, so a couple
// whose exact boxes touch is always reported (a few more whose boxes are within float rounding
// may be: the exact test decides them). The root's exact double box is kept too (box()).
#include "peelcd/core/aabb.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

// A function every node pair of a traversal calls (the box transforms): inlined even where the
// compiler would not (a shared library's call to it goes through the PLT otherwise).
#if defined(__GNUC__)
#define PEELCD_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define PEELCD_ALWAYS_INLINE inline
#endif

namespace peelcd {

// 8 triangles a leaf: half the nodes of 4 to refit and to visit (about an eighth off the large
// spheres' frames), the piles unchanged.
constexpr std::uint32_t kBvhLeafSize = 8;

// A closed box of floats that encloses the double box it was made from (each bound moved
// outward by about 2^-22 of itself). Empty: lo > hi.
struct FBox {
  float lo[3] = {INFINITY, INFINITY, INFINITY};
  float hi[3] = {-INFINITY, -INFINITY, -INFINITY};

  // A float <= d, and one >= d, within 2^-21 of d relative (d finite, or infinite). Below 1e37
  // without a branch on the rounding: the nearest float (within 2^-24 relative, or 2^-150 for
  // subnormals) moved out by 2.4e-7 > 2^-22 of itself plus the smallest normal float, which
  // covers its own error and the roundings of the widening (the tests check the enclosure).
  static float down(double d) {
    const float f = float(d);
    if (std::abs(f) < 1e37f) return f - (std::abs(f) * 2.4e-7f + 1.2e-38f);
    return double(f) > d ? step(f, -1) : f;
  }
  static float up(double d) {
    const float f = float(d);
    if (std::abs(f) < 1e37f) return f + (std::abs(f) * 2.4e-7f + 1.2e-38f);
    return double(f) < d ? step(f, +1) : f;
  }
  // The next float from the finite or infinite `f` toward +inf (dir > 0) or -inf: std::nextafter
  // without the library call (the refit rounds every box).
  static float step(float f, int dir) {
    if (f == 0.0f) return dir > 0 ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    // Away from zero: one more in the magnitude's bits; toward it: one less.
    if ((f > 0.0f) == (dir > 0)) ++bits;
    else --bits;
    std::memcpy(&f, &bits, sizeof bits);
    return f;
  }
  static FBox enclosing(const Aabb& b) {
    FBox f;
    for (int k = 0; k < 3; ++k) f.lo[k] = down(b.lo[k]), f.hi[k] = up(b.hi[k]);
    return f;
  }
  // The same box in doubles (exact).
  Aabb aabb() const {
    Aabb b;
    b.lo = Vec3(lo[0], lo[1], lo[2]);
    b.hi = Vec3(hi[0], hi[1], hi[2]);
    return b;
  }
  void merge(const FBox& o) {  // (no NaN here: plain comparisons, no libm call)
    for (int k = 0; k < 3; ++k) {
      lo[k] = o.lo[k] < lo[k] ? o.lo[k] : lo[k];
      hi[k] = o.hi[k] > hi[k] ? o.hi[k] : hi[k];
    }
  }
  // All six comparisons, combined without branches (a traversal's overlap tests follow the
  // geometry, which no branch predictor learns).
  bool overlaps(const FBox& o) const {
    return bool(int(lo[0] <= o.hi[0]) & int(o.lo[0] <= hi[0]) & int(lo[1] <= o.hi[1]) & int(o.lo[1] <= hi[1]) &
                int(lo[2] <= o.hi[2]) & int(o.lo[2] <= hi[2]));
  }
  bool overlaps(const Aabb& o) const {
    return lo[0] <= o.hi[0] && o.lo[0] <= hi[0] && lo[1] <= o.hi[1] && o.lo[1] <= hi[1] && lo[2] <= o.hi[2] &&
           o.lo[2] <= hi[2];
  }
  float max_extent() const {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    const float m = x > y ? x : y;
    return m > z ? m : z;
  }
};

struct BvhNode {
  FBox box;
  std::uint32_t first = 0;   // leaf: its BvhLeaf (Bvh::leaf()); internal: the right child
  std::uint32_t count = 0;   // leaf: triangles (>= 1); internal: 0
  bool leaf() const { return count != 0; }
};

// A leaf's triangles and their boxes, lane by lane (structure of arrays: one box is tested
// against all of a leaf's at once); lanes past the leaf's count hold empty boxes, which overlap
// nothing.
struct alignas(64) BvhLeaf {  // (its boxes on three whole cache lines, its triangles and bound on the fourth)
  float lo[3][kBvhLeafSize];
  float hi[3][kBvhLeafSize];
  std::uint32_t tri[kBvhLeafSize];
  // The leaf's node box while the tree's wide view is fresh (Bvh::wide_fresh()): the wide
  // traversal reads a leaf here, one line from its triangles, never its binary node.
  FBox bound;

  FBox box(std::uint32_t lane) const {
    FBox b;
    for (int k = 0; k < 3; ++k) b.lo[k] = lo[k][lane], b.hi[k] = hi[k][lane];
    return b;
  }
  void set(std::uint32_t lane, const FBox& b) {
    for (int k = 0; k < 3; ++k) lo[k][lane] = b.lo[k], hi[k][lane] = b.hi[k];
  }
};
static_assert(kBvhLeafSize == 8, "BvhLeaf's tests are written for 8 lanes");
static_assert(sizeof(BvhLeaf) == 256, "a BvhLeaf is four cache lines");

// Four children's boxes together (a 4-wide view of the binary tree, kept by Bvh alongside it):
// a wide node stands for a binary internal node at an even depth, its slots for that node's
// grandchildren (or a child that is a leaf), their boxes lane by lane so that one box is tested
// against all four at once. A slot's child is a wide node's index, or kBvhWideLeaf | a leaf's
// index (Bvh::leaf_at(); its box is the leaf's `bound`); an unused slot holds an empty box (it overlaps nothing) and kBvhWideNone.
// Two cache lines a node: the traversal of two trees in one frame (bvh_traverse_same_frame())
// reads two levels of boxes from them where the binary tree spreads them over up to six nodes.
constexpr std::uint32_t kBvhWideLeaf = 0x80000000u;
constexpr std::uint32_t kBvhWideNone = 0xffffffffu;

struct alignas(64) BvhWideNode {
  float lo[3][4];
  float hi[3][4];
  std::uint32_t child[4];
  std::uint32_t node;  // the binary node it stands for
};

// A tree that refits keep (a deforming body's in the World, a self tree of the frame API) is
// built again instead once refits have grown its internal nodes' summed extents
// (Bvh::growth()) past this factor of its build's: loose boxes overlap more and traversals
// visit more node pairs (the crumpled cloth drifting, refit only: growth 1.10 -> 1.25x the node
// pairs of its build, 1.26 -> 1.7x, 1.44 -> 2.2x; a build of its 100k triangles costs about a
// quarter of its self frame). Extents, not areas: a flat sheet's boxes gain a third side when
// it waves, which multiplies their areas while the tree stays as good.
constexpr double kBvhRebuildGrowth = 1.25;

class Bvh {
 public:
  // Builds over `triangles` of `vertices` (indices checked by the caller: validate_mesh).
  void build(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);
  // The same build split for threads: plan_build() takes the triangles' boxes and centroids and
  // splits the nodes above about `want` disjoint subtrees (one, the whole tree, for want <= 1),
  // returning their count; build_part(k) builds subtree k (parts may run concurrently);
  // finish_build() the boxes of the nodes above them, the leaves' corners and the wide view.
  // The tree is build()'s whatever `want` (each range is split as the whole build splits it).
  // `vertices` and `triangles` must stay as they are until finish_build() returns.
  std::size_t plan_build(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles, std::size_t want);
  void build_part(std::size_t k);
  void finish_build(const std::vector<Tri>& triangles);
  // Every box again from `vertices` (the same triangles, moved).
  void refit(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles);
  // The same in three steps, for callers that split the first two over threads (ranges of one
  // step may run concurrently): each vertex of [begin, end) rounded outward to a float box
  // (returns the exact box of those the triangles use), then the leaves [begin, end) of
  // leaves() from their corners' boxes, then every internal node, with `exact` the union of the first step's boxes. The vertices
  // are the tree's (the same count as at build; the triangles are the build's).
  Aabb refit_vertices(const std::vector<Vec3>& vertices, std::size_t begin, std::size_t end);
  void refit_leaves(const std::vector<Vec3>& vertices, std::size_t begin, std::size_t end);
  void refit_nodes(const Aabb& exact);
  // The third step split by subtrees, for threads: plan_parts(want) picks about `want`
  // disjoint subtrees (one, the whole tree, for want <= 1; fewer in a small tree) and returns
  // their count; refit_part(k) refits subtree k's internal nodes (parts may run concurrently,
  // after every leaf's refit); refit_top() then the nodes above them, as refit_nodes(exact)
  // would. The same `want` gives the same parts whatever the threads, so growth() sums in the
  // same order.
  std::size_t plan_parts(std::size_t want);
  void refit_part(std::size_t k);
  void refit_top(const Aabb& exact);
  // The first step for vertices that are not yet the tree's (a caller that checks new vertices
  // and keeps them in one pass over them): each vertex of [begin, end) of `vertices` checked
  // finite, rounded as refit_vertices() rounds it and, with `copy`, copied to copy[v]; at the
  // first vertex with a coordinate not finite the pass stops and `bad` is its index (else
  // `end`). Returns the exact box of the vertices loaded that the triangles use. Until every
  // range is loaded without a bad vertex, the next refit must start from refit_vertices().
  // Without `round`, the vertices are checked, copied and boxed but not rounded (a caller whose
  // refit may not come: the next refit, if any, starts from refit_vertices()).
  Aabb load_vertices(const std::vector<Vec3>& vertices, Vec3* copy, std::size_t begin, std::size_t end,
                     std::size_t& bad, bool round = true);
  // Only the boxes of `changed` triangles (any order, repeats allowed), their leaves and their
  // ancestors: O(changed * depth).
  void refit(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles,
             const std::vector<std::uint32_t>& changed);

  bool empty() const { return nodes_.empty(); }
  std::size_t triangles() const { return leaf_of_.size(); }
  std::size_t leaves() const { return leaves_.size(); }
  // The exact box of the triangles' corners (empty() for an empty tree).
  Aabb box() const { return nodes_.empty() ? Aabb{} : box_; }
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  const BvhLeaf& leaf(const BvhNode& node) const { return leaves_[node.first]; }
  const BvhLeaf& leaf_at(std::uint32_t l) const { return leaves_[l]; }
  std::uint32_t parent(std::uint32_t node) const { return parents_[node]; }  // the root's is itself (0)
  const std::vector<std::uint32_t>& order() const { return order_; }  // triangles, leaf by leaf
  // A leaf's triangles (node.count of them, lane by lane) as the build's corner indices.
  const Tri* leaf_corners(const BvhNode& node) const { return corners_.data() + leaf_first_[node.first]; }
  FBox triangle_box(std::uint32_t t) const { return leaves_[nodes_[leaf_of_[t]].first].box(lane_of_[t]); }
  std::size_t depth() const { return depth_; }
  // The 4-wide view (BvhWideNode; empty when the root is a leaf), its root at 0. Its layout is
  // made by every build; its boxes equal the binary nodes' while wide_fresh(): after a build,
  // a partial refit of a fresh view, or sync_wide(). A whole refit leaves them stale (copying
  // every box again costs a tree refitted every frame more than its traversal gains: about 7%
  // of the waving 330k-triangle spheres' frame against under 1% back); keep_wide_if_still() syncs a tree that
  // has not changed since its last call (the World calls it once a frame for the trees it
  // traverses in one frame). wide_of(n): the wide node binary node n stands for, or
  // kBvhWideNone (a leaf, or an internal node at an odd depth: its children are its parent's
  // slots).
  const std::vector<BvhWideNode>& wide() const { return wide_; }
  std::uint32_t wide_of(std::uint32_t node) const { return wide_of_[node]; }
  bool wide_fresh() const { return wide_fresh_; }
  void sync_wide();
  // What the wide traversal reads (the wide view and the leaves), in bytes; and a request for it
  // in address order (prefetches, no result): a small tree that other work evicted between
  // frames then arrives as one stream, where the traversal would wait on one line after another.
  std::size_t wide_bytes() const { return wide_.size() * sizeof(BvhWideNode) + leaves_.size() * sizeof(BvhLeaf); }
  void prefetch_wide() const;
  void keep_wide_if_still() {
    if (!wide_fresh_ && changes_ == changes_seen_) sync_wide();
    changes_seen_ = changes_;
  }
  // How far refits have loosened the tree: its internal nodes' summed extents (x + y + z of
  // each box) after the last whole refit against the same sum at its build (1 at a build; a
  // partial refit leaves it). A tree built for a tangle stays as loose when it unfolds: the
  // measure is against its own build, not against a tree built now.
  double growth() const { return size_at_build_ > 0.0 ? size_ / size_at_build_ : 1.0; }
  // After a whole refit: builds the tree again when refits grew it past kBvhRebuildGrowth (the
  // one rule of every tree that refits keep); returns whether it did.
  bool rebuild_if_grown(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles) {
    if (!grown()) return false;
    build(vertices, triangles);
    return true;
  }
  bool grown() const { return growth() > kBvhRebuildGrowth; }  // rebuild_if_grown() would build

  // The triangles whose (float, outward-rounded) boxes touch `box` (closed, in the tree's frame),
  // ascending, into `out`: every triangle whose exact box touches it, and possibly some within
  // float rounding of it.
  void query(const Aabb& box, std::vector<std::uint32_t>& out) const;

 private:
  struct BuildItem {  // a triangle's centroid and index, moved as one by the build's partitions
    double c[3];
    std::uint32_t t;
  };
  // A subtree of a build: its triangles' range of build_items_, its root's node, parent and level,
  // its first leaf (each node's place in depth-first order follows from the counts before it);
  // `depth` the deepest level under it, once built.
  struct BuildPart {
    std::uint32_t begin, end, node, parent, leaf;
    std::size_t level, depth;
  };
  std::uint32_t split_range(std::uint32_t begin, std::uint32_t end);  // sorts a range about its split; returns it
  void build_node(const BuildPart& at, std::size_t& depth);
  void refit_node(std::uint32_t n);
  double merge_children(std::uint32_t i);  // an internal node's box from its children's; returns its extents
  std::uint32_t build_wide(std::uint32_t node);  // the wide node for internal `node` and those under it
  static void put_slot(BvhWideNode& w, std::uint32_t slot, const FBox& box) {
    for (int k = 0; k < 3; ++k) w.lo[k][slot] = box.lo[k], w.hi[k][slot] = box.hi[k];
  }
  // Binary node n's box into its wide slot (if it is one) and, a leaf, into its leaf's bound
  // (the view fresh).
  void set_slot(std::uint32_t n) {
    const std::uint32_t s = slot_of_[n];
    if (s != kBvhWideNone) put_slot(wide_[s >> 2], s & 3u, nodes_[n].box);
    if (nodes_[n].leaf()) leaves_[nodes_[n].first].bound = nodes_[n].box;
  }
  template <bool Load, bool Round>
  Aabb round_vertices(const std::vector<Vec3>& vertices, Vec3* copy, std::size_t begin, std::size_t end,
                      std::size_t& bad);
  std::vector<BvhNode> nodes_;
  std::vector<BvhLeaf> leaves_;
  std::vector<BvhWideNode> wide_;
  std::vector<std::uint32_t> wide_of_;  // node -> its wide node, or kBvhWideNone
  std::vector<std::uint32_t> slot_of_;  // node -> 4 * wide node + slot holding its box, or kBvhWideNone
  bool wide_fresh_ = false;             // the wide view's boxes equal the nodes'
  std::uint64_t changes_ = 0;           // builds and refits so far
  std::uint64_t changes_seen_ = ~std::uint64_t(0);  // changes_ at the last keep_wide_if_still()
  std::vector<std::uint32_t> leaf_node_;  // leaf -> its node
  struct alignas(16) VertexBox {
    float lo[4], hi[4];
  };
  std::vector<VertexBox> vertex_boxes_;  // vertex -> its coordinates rounded down and up (the refit's)
  std::vector<Tri> corners_;         // the triangles' corners in order_'s order: leaf by leaf, the refit's reads
  std::vector<std::uint32_t> leaf_first_;  // leaf -> its first triangle's place in order_
  std::vector<std::uint8_t> unused_;     // vertex -> no triangle uses it (empty: all are used)
  std::vector<std::uint32_t> parents_;    // node -> its parent
  std::vector<std::uint32_t> order_;
  std::vector<std::uint32_t> leaf_of_;  // triangle -> its leaf node
  std::vector<std::uint8_t> lane_of_;   // triangle -> its lane in the leaf
  Aabb box_;                            // the exact box of every corner
  std::vector<std::uint8_t> dirty_;     // scratch of the partial refit, per node
  std::vector<std::uint32_t> stack_;    // scratch of the partial refit
  std::size_t depth_ = 0;
  double size_ = 0.0, size_at_build_ = 0.0;  // growth()'s sums
  // plan_parts(): the subtrees' roots (ascending), their summed extents, the nodes above
  // them (descending).
  std::vector<std::uint32_t> part_roots_, part_top_;
  std::vector<double> part_sizes_;
  // plan_build(): the items and boxes (kept between builds), the subtrees, the nodes above them.
  std::vector<BuildItem> build_items_;
  std::vector<FBox> build_boxes_;
  std::vector<BuildPart> build_parts_;
  std::vector<std::uint32_t> build_top_;
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
  PEELCD_ALWAYS_INLINE Aabb to_a(const Aabb& b) const { return identity ? b : moved(b, linear, abs_linear, translation, reach); }
  // A's box as seen from B, the same way.
  PEELCD_ALWAYS_INLINE Aabb to_b(const Aabb& a) const { return identity ? a : moved(a, inv_linear, inv_abs_linear, inv_translation, reach); }
  // A's box `a` and B's box `b` (whose image in A's frame is `b_in_a`) may overlap: tested in
  // both frames (a separating axis among A's three or B's three).
  PEELCD_ALWAYS_INLINE bool overlap(const Aabb& a, const Aabb& b_in_a, const Aabb& b) const {
    return a.overlaps(b_in_a) && (identity || to_b(a).overlaps(b));
  }
  static BvhRelation between(const Eigen::Affine3d& pose_a, const Eigen::Affine3d& pose_b);

  // The two maps again in floats, for the posed traversal's box transforms four lanes at once
  // (bvh_traverse.h: FloatCarry, which states the error bound): columns of the linear part and
  // of its magnitudes, the translation and its magnitude (lane 3 zero), and the growth every
  // carried box gets besides its relative one (`reach`'s, and the floats' underflow).
  struct FloatMap {
    alignas(16) float col[3][4];
    alignas(16) float abs_col[3][4];
    alignas(16) float t[4];
    alignas(16) float abs_t[4];
    float grow = 0.0f;
  };
  FloatMap float_to_a, float_to_b;
  // Whether the float maps may be used: every entry of the linear parts 0 or a normal float up
  // to 1e6, the translations and `reach` below 1e30 (the traversal also checks the trees'
  // boxes: below 1e30 in magnitude, so no sum or product overflows).
  bool float_ok = false;
  static constexpr double kFloatRange = 1e30;
  // Inlined: the traversals call it at every node pair.
  PEELCD_ALWAYS_INLINE static Aabb moved(const Aabb& box, const Eigen::Matrix3d& linear, const Eigen::Matrix3d& abs_linear,
                    const Vec3& translation, double reach) {
    const Vec3 c = box.center(), e = 0.5 * box.extent();
    const Vec3 center = linear * c + translation;
    const Vec3 half = abs_linear * e;
    // Rounding of the products above: a relative 1e-9 of the magnitudes involved covers it.
    const double grow = 1e-9 * (center.cwiseAbs().maxCoeff() + half.maxCoeff() + reach) + 1e-300;
    Aabb out;
    out.lo = center - half - Vec3::Constant(grow);
    out.hi = center + half + Vec3::Constant(grow);
    return out;
  }
};

// A pair of nodes (A's, B's) still to visit.
using BvhNodePair = std::pair<std::uint32_t, std::uint32_t>;

// A node pair on the traversal's stack, with B's box as seen from A (computed once, when the
// pair is pushed; descending into A's children keeps it).
struct BvhStackEntry {
  std::uint32_t a, b;
  FBox b_in_a;  // rounded outward
};

// Splits the traversal of (a, b) into at least `tasks` independent node pairs where the trees
// allow (breadth first from the roots; leaf pairs and disjoint pairs settled on the way: the
// disjoint dropped, the leaf pairs appended to `tasks_out` like any other).
void bvh_split(const Bvh& a, const Bvh& b, const BvhRelation& rel, std::size_t tasks,
               std::vector<BvhNodePair>& tasks_out);
// The same with the walk's levels kept in `scratch` (a caller that splits every frame: no
// allocation once they have grown).
struct BvhSplitScratch {
  std::vector<BvhNodePair> level, next;
};
void bvh_split(const Bvh& a, const Bvh& b, const BvhRelation& rel, std::size_t tasks,
               std::vector<BvhNodePair>& tasks_out, BvhSplitScratch& scratch);
// The same for the self traversal of one tree (bvh_self_traverse()): a node against itself gives
// its two children each against itself and, where their boxes overlap, the one against the other;
// two nodes as bvh_split() on one frame. Every couple of the whole self traversal is under
// exactly one of the node pairs given.
void bvh_self_split(const Bvh& tree, std::size_t tasks, std::vector<BvhNodePair>& tasks_out, BvhSplitScratch& scratch);

// The pair traversals over these trees (bvh_traverse(), bvh_traverse_same_frame(),
// bvh_self_traverse()) are the library's own: core/exact/bvh_traverse.h.

}  // namespace peelcd
