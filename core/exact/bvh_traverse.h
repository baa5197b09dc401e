#pragma once
// The pair traversals of two trees (peelcd/core/exact/bvh.h), private to the library: one kernel
// (traverse_pairs()) that pops node pairs and hands each to a frame policy, one leaf-pair
// visitor (leaf_couples()) that tests one leaf's triangle boxes against another's eight at once,
// and the three frames:
//   SameFrame  two trees in one frame (two deforming bodies, a body against a copy in world
//              space): float boxes compared as they are;
//   Posed      B's tree in its own frame (BvhRelation): boxes carried into the other frame and
//              rounded outward, tested in both frames;
//   Self       one tree against itself: a node against itself descends into its children, each
//              couple once.
// The SIMD box tests and cache prefetches live here, not in the public header.
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/exact/self.h"

#include <cstdint>
#include <vector>

#if defined(__SSE__) || defined(_M_X64)
#include <emmintrin.h>
#endif

namespace peelcd {
namespace bvh_detail {

// The lanes of `leaf` whose boxes overlap `box` (closed), as bits (lane i: bit i). Empty lanes
// never do.
inline unsigned overlap_mask(const FBox& box, const BvhLeaf& leaf) {
#if defined(__SSE__) || defined(_M_X64)
  unsigned mask = 0;
  for (int h = 0; h < 2; ++h) {
    __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (int k = 0; k < 3; ++k) {
      const __m128 lo = _mm_load_ps(leaf.lo[k] + 4 * h), hi = _mm_load_ps(leaf.hi[k] + 4 * h);
      ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmple_ps(_mm_set1_ps(box.lo[k]), hi), _mm_cmple_ps(lo, _mm_set1_ps(box.hi[k]))));
    }
    mask |= unsigned(_mm_movemask_ps(ok)) << (4 * h);
  }
  return mask;
#else
  unsigned mask = 0;
  for (std::uint32_t i = 0; i < kBvhLeafSize; ++i) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) ok = ok && box.lo[k] <= leaf.hi[k][i] && leaf.lo[k][i] <= box.hi[k];
    mask |= unsigned(ok) << i;
  }
  return mask;
#endif
}

// The lowest set bit's index, and the mask without it.
inline unsigned take_lane(unsigned& mask) {
  const unsigned lane = unsigned(__builtin_ctz(mask));
  mask &= mask - 1;
  return lane;
}

// The node indices of a traversal's stack entry.
inline BvhNodePair node_indices(const BvhNodePair& e) { return e; }
inline BvhNodePair node_indices(const BvhStackEntry& e) { return {e.a, e.b}; }

inline void prefetch(const void* p) { __builtin_prefetch(p); }

// Asks for a leaf's lines ahead of its test (a traversal that pushes a pair of leaves).
inline void prefetch_leaf(const Bvh& tree, const BvhNode& node) {
  const char* p = reinterpret_cast<const char*>(&tree.leaf(node));
  for (std::size_t k = 0; k < sizeof(BvhLeaf); k += 64) prefetch(p + k);
}

// The leaf-pair visitor: for each of the first `count` lanes u of `la`, box_of(u, box) sets the
// box to test against `lb` and returns the lanes of `lb` it may pair with (0: none); each of
// those whose box overlaps gives fn(la.tri[u], lb.tri[lane]).
template <class BoxOf, class Fn>
inline void leaf_couples(const BvhLeaf& la, std::uint32_t count, const BvhLeaf& lb, BoxOf&& box_of, Fn&& fn) {
  for (std::uint32_t u = 0; u < count; ++u) {
    FBox box;
    const unsigned allowed = box_of(u, box);
    if (allowed == 0) continue;
    for (unsigned m = overlap_mask(box, lb) & allowed; m;) fn(la.tri[u], lb.tri[take_lane(m)]);
  }
}

// Two leaves of trees in one frame, each node's box the union of its lanes' (Bvh keeps them so):
// every couple of lanes whose boxes overlap, fn(tri_a, tri_b) in leaf_couples()'s order. A
// couple's boxes overlap only where A's lane reaches B's node box and B's lane A's (each box
// lies in its node's), so those two masks, eight lanes each at once, come first: the lanes of A
// outside B's box skip their test against B's eight, those of B outside A's box are masked off.
template <class Fn>
inline void leaf_pair_couples(const BvhLeaf& la, const FBox& box_a, const BvhLeaf& lb, const FBox& box_b, Fn&& fn) {
  const unsigned allowed = overlap_mask(box_a, lb);
  if (allowed == 0) return;
  for (unsigned us = overlap_mask(box_b, la); us;) {
    const unsigned u = take_lane(us);
    for (unsigned m = overlap_mask(la.box(u), lb) & allowed; m;) fn(la.tri[u], lb.tri[take_lane(m)]);
  }
}

// The stack is stack[0, top), grown here as needed.
template <class Entry>
inline void reserve(std::vector<Entry>& stack, std::size_t top, std::size_t more) {
  if (stack.size() < top + more) stack.resize(2 * top + 64);
}

// One step down from node pair (i, j) of two trees in one frame, not both leaves: the larger
// node's children whose boxes overlap the other node's, pushed with it. A child is written in
// any case and kept by moving top past it (no branch on the overlap). A child pair of two leaves
// has its leaves' lines asked for, kept or not (a kept one is popped soon: the stack is last in,
// first out; asking only for kept ones would branch on the overlap again); a child's right
// child (its left one is next to it) is asked for in any case, ahead of the child's own descent
// (for a leaf, whose `first` is a leaf index, the hint is wasted, which costs less than a branch).
PEELCD_ALWAYS_INLINE void descend_same_frame(const Bvh& a, const Bvh& b, std::uint32_t i, std::uint32_t j,
                                             std::vector<BvhNodePair>& stack, std::size_t& top) {
  reserve(stack, top, 2);
  const auto& na = a.nodes();
  const auto& nb = b.nodes();
  const BvhNode& x = na[i];
  const BvhNode& y = nb[j];
  if (y.leaf() || (!x.leaf() && x.box.max_extent() >= y.box.max_extent())) {
    for (const std::uint32_t c : {i + 1, x.first}) {
      const bool keep = na[c].box.overlaps(y.box);
      stack[top] = {c, j};
      top += keep;
      if (na[c].leaf() & y.leaf()) prefetch_leaf(a, na[c]), prefetch_leaf(b, y);
      prefetch(&na[na[c].first]);
    }
  } else {
    for (const std::uint32_t c : {j + 1, y.first}) {
      const bool keep = x.box.overlaps(nb[c].box);
      stack[top] = {i, c};
      top += keep;
      if (x.leaf() & nb[c].leaf()) prefetch_leaf(a, x), prefetch_leaf(b, nb[c]);
      prefetch(&nb[nb[c].first]);
    }
  }
}

// Two trees in one frame: the stack holds node pairs alone.
struct SameFrame {
  using Entry = BvhNodePair;
  const Bvh& a;
  const Bvh& b;
  bool admit(BvhNodePair start, Entry& e) const {
    e = start;
    return a.nodes()[start.first].box.overlaps(b.nodes()[start.second].box);
  }
  // Invariant: the two nodes' boxes overlap (tested before the push).
  template <class Fn>
  void leaves(const Entry& /*e*/, const BvhNode& x, const BvhNode& y, Fn& fn) const {
    leaf_pair_couples(a.leaf(x), x.box, b.leaf(y), y.box, fn);
  }
  void descend(const Entry& e, std::vector<Entry>& stack, std::size_t& top) const {
    descend_same_frame(a, b, e.first, e.second, stack, top);
  }
};

// B's tree posed against A's: each entry carries B's node box as seen from A (computed once,
// when the pair is pushed; descending into A's children keeps it). A node pair is pushed when
// the boxes overlap in A's frame (and, descending B, in B's too); a couple is reported when A's
// triangle box overlaps B's leaf in A's frame and, carried into B's frame and rounded outward,
// B's triangle box there (one transform per triangle of A, B's eight boxes tested at once).
// Boxes carried through a pose are boxes of boxes: some couples whose own boxes do not overlap
// are reported (the exact test decides).
struct Posed {
  using Entry = BvhStackEntry;
  const Bvh& a;
  const Bvh& b;
  const BvhRelation& rel;
  bool admit(BvhNodePair start, Entry& e) const {
    const Aabb yb = rel.to_a(b.nodes()[start.second].box.aabb());
    e = {start.first, start.second, yb};
    return rel.overlap(a.nodes()[start.first].box.aabb(), yb, b.nodes()[start.second].box.aabb());
  }
  // Invariant: A's node box overlaps e.b_in_a (tested before the push).
  template <class Fn>
  void leaves(const Entry& e, const BvhNode& x, const BvhNode& y, Fn& fn) const {
    const BvhLeaf& la = a.leaf(x);
    if (rel.identity) {  // one frame: the float boxes compared as they are
      leaf_couples(la, x.count, b.leaf(y), [&](std::uint32_t u, FBox& box) {
        box = la.box(u);
        return box.overlaps(e.b_in_a) ? ~0u : 0u;
      }, fn);
      return;
    }
    leaf_couples(la, x.count, b.leaf(y), [&](std::uint32_t u, FBox& box) {
      const Aabb ba = la.box(u).aabb();
      if (!ba.overlaps(e.b_in_a)) return 0u;
      box = FBox::enclosing(rel.to_b(ba));  // A's triangle box seen from B, rounded outward
      return box.overlaps(y.box) ? ~0u : 0u;
    }, fn);
  }
  PEELCD_ALWAYS_INLINE void descend(const Entry& e, std::vector<Entry>& stack, std::size_t& top) const {
    reserve(stack, top, 2);
    const auto& na = a.nodes();
    const auto& nb = b.nodes();
    const BvhNode& x = na[e.a];
    const BvhNode& y = nb[e.b];
    if (y.leaf() || (!x.leaf() && double(x.box.max_extent()) >= e.b_in_a.extent().maxCoeff())) {
      for (const std::uint32_t c : {e.a + 1, x.first})  // B's box is in A's frame either way
        if (na[c].box.overlaps(e.b_in_a)) stack[top++] = {c, e.b, e.b_in_a};
    } else if (rel.identity) {
      for (const std::uint32_t c : {e.b + 1, y.first})
        if (x.box.overlaps(nb[c].box)) stack[top++] = {e.a, c, nb[c].box.aabb()};
    } else {
      const Aabb x_in_b = rel.to_b(x.box.aabb());
      for (const std::uint32_t c : {e.b + 1, y.first}) {
        const FBox& cb = nb[c].box;
        if (!cb.overlaps(x_in_b)) continue;
        const Aabb yb = rel.to_a(cb.aabb());
        if (x.box.overlaps(yb)) stack[top++] = {e.a, c, yb};
      }
    }
  }
};

// The corner ids of a leaf's lanes, lane by lane (structure of arrays, as the leaf's boxes):
// vertex indices, or their representatives where `rep` is not null. sharing(c) gives the lanes
// whose triangle shares an id with corners `c` as bits (lane i: bit i), compared eight at once.
struct LeafCornerIds {
  alignas(16) std::uint32_t v[3][kBvhLeafSize];
  LeafCornerIds(const Tri* corners, std::uint32_t count, const std::uint32_t* rep) {
    for (std::uint32_t lane = 0; lane < kBvhLeafSize; ++lane)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t c = lane < count ? corners[lane][k] : 0u;  // empty lanes: masked off by their boxes
        v[k][lane] = rep && lane < count ? rep[c] : c;
      }
  }
  unsigned sharing(const std::uint32_t c[3]) const {
#if defined(__SSE2__) || defined(_M_X64)
    __m128i lo = _mm_setzero_si128(), hi = _mm_setzero_si128();
    for (int i = 0; i < 3; ++i) {
      const __m128i x = _mm_set1_epi32(int(c[i]));
      for (int k = 0; k < 3; ++k) {
        lo = _mm_or_si128(lo, _mm_cmpeq_epi32(x, _mm_load_si128(reinterpret_cast<const __m128i*>(v[k]))));
        hi = _mm_or_si128(hi, _mm_cmpeq_epi32(x, _mm_load_si128(reinterpret_cast<const __m128i*>(v[k] + 4))));
      }
    }
    return unsigned(_mm_movemask_ps(_mm_castsi128_ps(lo))) | unsigned(_mm_movemask_ps(_mm_castsi128_ps(hi))) << 4;
#else
    unsigned mask = 0;
    for (std::uint32_t lane = 0; lane < kBvhLeafSize; ++lane) {
      bool same = false;
      for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) same |= c[i] == v[k][lane];
      mask |= unsigned(same) << lane;
    }
    return mask;
#endif
  }
};

// One tree against itself: a node against itself pushes its children each against itself and
// against each other (if their boxes overlap); a leaf against itself pairs each lane with the
// lanes after it; other pairs descend as SameFrame's. With `drop_adjacent`, couples that share
// a corner (vertex indices, or their representatives `rep` where not null) are dropped in the
// leaf-pair visit, eight at once, and never reach fn.
struct Self {
  using Entry = BvhNodePair;
  const Bvh& tree;
  bool drop_adjacent = false;
  const std::uint32_t* rep = nullptr;
  bool admit(BvhNodePair start, Entry& e) const {
    e = start;
    return !tree.empty();
  }
  template <class Fn>
  void leaves(const Entry& e, const BvhNode& x, const BvhNode& y, Fn& fn) const {
    const BvhLeaf& lx = tree.leaf(x);
    const bool same = e.first == e.second;
    if (!drop_adjacent) {
      if (same)  // lanes after u (empty lanes never overlap)
        leaf_couples(lx, x.count, lx, [&](std::uint32_t u, FBox& box) { return box = lx.box(u), ~0u << (u + 1); }, fn);
      else
        leaf_pair_couples(lx, x.box, tree.leaf(y), y.box, fn);
      return;
    }
    const BvhLeaf& ly = tree.leaf(y);
    // Two leaves: only A's lanes that reach B's node box, against B's that reach A's (as
    // leaf_pair_couples()), the corner ids read only when some do.
    const unsigned allowed = same ? ~0u : overlap_mask(x.box, ly);
    unsigned us = same ? (1u << x.count) - 1u : overlap_mask(y.box, lx);
    if (allowed == 0 || us == 0) return;
    const LeafCornerIds ids(tree.leaf_corners(y), y.count, rep);
    const Tri* cx = tree.leaf_corners(x);
    while (us) {
      const unsigned u = take_lane(us);
      unsigned m = overlap_mask(lx.box(u), ly) & allowed & (same ? ~0u << (u + 1) : ~0u);
      if (m == 0) continue;
      std::uint32_t c[3];
      for (int k = 0; k < 3; ++k) c[k] = rep ? rep[cx[u][k]] : cx[u][k];
      for (m &= ~ids.sharing(c); m;) fn(lx.tri[u], ly.tri[take_lane(m)]);
    }
  }
  void descend(const Entry& e, std::vector<Entry>& stack, std::size_t& top) const {
    if (e.first != e.second) return descend_same_frame(tree, tree, e.first, e.second, stack, top);
    const auto& n = tree.nodes();
    const std::uint32_t l = e.first + 1, r = n[e.first].first;
    reserve(stack, top, 3);
    stack[top++] = {l, l};
    stack[top++] = {r, r};
    stack[top] = {l, r};
    top += n[l].box.overlaps(n[r].box);
  }
};

// The kernel: every node pair under `start` that the frame admits, popped last in, first out;
// two leaves go to the frame's leaf-pair visit, other pairs to its descent. Returns the node
// pairs visited.
template <class Frame, class Fn>
std::size_t traverse_pairs(const Frame& frame, const Bvh& a, const Bvh& b, BvhNodePair start,
                           std::vector<typename Frame::Entry>& stack, Fn& fn) {
  typename Frame::Entry first;
  if (!frame.admit(start, first)) return a.empty() || b.empty() ? 0 : 1;
  reserve(stack, 0, 64);
  stack[0] = first;
  std::size_t top = 1, visited = 0;
  const auto& na = a.nodes();
  const auto& nb = b.nodes();
  while (top != 0) {
    const typename Frame::Entry e = stack[--top];
    ++visited;
    const auto [i, j] = node_indices(e);
    const BvhNode& x = na[i];
    const BvhNode& y = nb[j];
    if (x.leaf() && y.leaf())
      frame.leaves(e, x, y, fn);
    else
      frame.descend(e, stack, top);
  }
  return visited;
}

}  // namespace bvh_detail

// Every couple (triangle of a, triangle of b) under the node pair `start` whose boxes overlap
// (B's through `rel`): fn(tri_a, tri_b). `stack` is scratch. Returns the node pairs visited.
template <class Fn>
std::size_t bvh_traverse(const Bvh& a, const Bvh& b, const BvhRelation& rel, BvhNodePair start,
                         std::vector<BvhStackEntry>& stack, Fn&& fn) {
  return bvh_detail::traverse_pairs(bvh_detail::Posed{a, b, rel}, a, b, start, stack, fn);
}

// bvh_traverse() for two trees in one frame (BvhRelation::identity): float boxes compared as
// they are, the stack of node pairs alone. The same couples.
template <class Fn>
std::size_t bvh_traverse_same_frame(const Bvh& a, const Bvh& b, BvhNodePair start, std::vector<BvhNodePair>& stack,
                                    Fn&& fn) {
  return bvh_detail::traverse_pairs(bvh_detail::SameFrame{a, b}, a, b, start, stack, fn);
}

// Every couple of distinct triangles of one tree whose boxes overlap (closed): fn(t, u), once
// per couple, in no particular order of t and u (the self-collision search: the caller drops
// adjacent couples). `stack` is scratch. Returns the node pairs visited.
template <class Fn>
std::size_t bvh_self_traverse(const Bvh& tree, std::vector<BvhNodePair>& stack, Fn&& fn) {
  return bvh_detail::traverse_pairs(bvh_detail::Self{tree}, tree, tree, BvhNodePair{0u, 0u}, stack, fn);
}

// bvh_self_traverse() without the couples that share a corner: vertex indices (rep null:
// SelfAdjacency::index), or their representatives rep[v] (vertex_representatives()), decided in
// the leaf-pair visit for eight couples at once (triangles_adjacent()'s answer). The tree's
// build triangles are the mesh's.
template <class Fn>
std::size_t bvh_self_traverse_apart(const Bvh& tree, const std::uint32_t* rep, std::vector<BvhNodePair>& stack,
                                    Fn&& fn) {
  return bvh_detail::traverse_pairs(bvh_detail::Self{tree, true, rep}, tree, tree, BvhNodePair{0u, 0u}, stack, fn);
}

// Every candidate self couple of `mesh` (two triangles whose closed boxes overlap and that are
// not adjacent) through the kept tree `st`, brought to `mesh` first and traversed against itself
// (no n^2): fn(t, u) with t < u, in traversal order. Returns the node pairs visited.
template <class Fn>
std::size_t self_overlap_visit(const Mesh& mesh, SelfTree& st, const std::vector<std::uint32_t>& rep, Fn&& fn) {
  st.update(mesh);
  const std::uint32_t* r = representatives_or_null(rep);
  return bvh_self_traverse_apart(st.tree, r, st.stack, [&](std::uint32_t x, std::uint32_t y) {
    if (x < y)
      fn(x, y);
    else
      fn(y, x);
  });
}

}  // namespace peelcd
