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
#include "peelcd/core/pairs.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>
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

// A sink of couples kept as pack_pair keys, appended to `out` (the World's candidates): a leaf
// visit hands it a lane of A with B's lanes as a mask (lanes()), and each of B's eight lanes is
// written with the count advanced by its bit, no branch on which lanes overlap (an untrained
// predictor guesses those counts badly: where other work ran between frames, as in the bench).
// The keys gather in a small buffer moved to `out` in bulk; finish() moves the rest. The same
// couples in the same order as fn(a, b) per lane.
class CoupleKeys {
 public:
  explicit CoupleKeys(std::vector<std::uint64_t>& out) : out_(out) {}
  CoupleKeys(const CoupleKeys&) = delete;
  CoupleKeys& operator=(const CoupleKeys&) = delete;
  void operator()(std::uint32_t a, std::uint32_t b) {
    if (n_ == kBuffer) finish();
    buf_[n_++] = pack_pair(a, b);
  }
  void lanes(std::uint32_t a, const std::uint32_t (&tris)[kBvhLeafSize], unsigned mask) {
    if (n_ > kBuffer - kBvhLeafSize) finish();
    const std::uint64_t hi = pack_pair(a, 0);
    for (std::uint32_t k = 0; k < kBvhLeafSize; ++k) {
      buf_[n_] = hi | tris[k];
      n_ += (mask >> k) & 1u;
    }
  }
  void finish() {
    out_.insert(out_.end(), buf_, buf_ + n_);
    n_ = 0;
  }

 private:
  static constexpr std::size_t kBuffer = 256;
  std::vector<std::uint64_t>& out_;
  std::size_t n_ = 0;
  std::uint64_t buf_[kBuffer];
};

// fn(a, tris[lane]) for each lane set in `mask`, lowest first (a CoupleKeys sink takes them at once).
template <class Fn>
PEELCD_ALWAYS_INLINE void couples_of_lane(Fn& fn, std::uint32_t a, const std::uint32_t (&tris)[kBvhLeafSize],
                                          unsigned mask) {
  if constexpr (std::is_same_v<std::decay_t<Fn>, CoupleKeys>)
    fn.lanes(a, tris, mask);
  else
    while (mask) fn(a, tris[take_lane(mask)]);
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
    couples_of_lane(fn, la.tri[u], lb.tri, overlap_mask(box, lb) & allowed);
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
    couples_of_lane(fn, la.tri[u], lb.tri, overlap_mask(la.box(u), lb) & allowed);
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
      if (int(na[c].leaf()) & int(y.leaf())) prefetch_leaf(a, na[c]), prefetch_leaf(b, y);
      prefetch(&na[na[c].first]);
    }
  } else {
    for (const std::uint32_t c : {j + 1, y.first}) {
      const bool keep = x.box.overlaps(nb[c].box);
      stack[top] = {i, c};
      top += keep;
      if (int(x.leaf()) & int(nb[c].leaf())) prefetch_leaf(a, x), prefetch_leaf(b, nb[c]);
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

// How the posed traversal carries a box into the other tree's frame: the box enclosing its
// image, rounded outward to floats. DoubleCarry goes through BvhRelation's doubles (any pose);
// FloatCarry computes in floats, four lanes at once, where BvhRelation::float_ok and the trees'
// boxes allow (bvh_traverse() chooses).
struct DoubleCarry {
  const BvhRelation& rel;
  PEELCD_ALWAYS_INLINE FBox to_a(const FBox& b) const { return FBox::enclosing(rel.to_a(b.aabb())); }
  PEELCD_ALWAYS_INLINE FBox to_b(const FBox& a) const { return FBox::enclosing(rel.to_b(a.aabb())); }
  // The lanes `lanes` (bits) of `leaf` carried into B's frame, lane by lane into `out`; the
  // other lanes of `out` empty.
  void leaf_to_b(const BvhLeaf& leaf, unsigned lanes, BvhLeaf& out) const {
    for (std::uint32_t u = 0; u < kBvhLeafSize; ++u) out.set(u, (lanes >> u) & 1u ? to_b(leaf.box(u)) : FBox{});
  }
};

// The float transform of a box [lo, hi] by p -> L p + t (u = 2^-24, float's unit roundoff; the
// box's coordinates, L's entries and t bounded as BvhRelation::float_ok and bvh_traverse()
// require, so nothing overflows and L's nonzero entries are normal floats). With c = (lo + hi) / 2,
// e = (hi - lo) / 2, a = max(|lo|, |hi|) = |c| + e (exact) and m = |L| a + |t|, the box's image
// lies in [center - half, center + half] computed as L c + t and |L| e, but for:
//   c and e rounded: the box moves and shrinks by at most u a, its image by u m;
//   L and t rounded to floats: u m in the center, u m in the half extent;
//   the two sums of products (four and three terms): gamma_4 m and gamma_3 m, about 7u m;
//   the final half + grow and center -/+ it: at most 3.3u m.
// In all below 14u m; the growth is 2^-19 m = 32u m (m itself computed in floats, a few u
// low at most), plus the relation's fixed growth (the world coordinates' rounding, `reach`,
// and 1e-37 for any product that underflows: at most 2^-150 each). The rest of the growth
// covers the relation's own doubles (an inverse pose loses cond x 2^-53, below 1e-12 for the
// poses the World traverses posed: kPosedConditionLimit). The test holds carried boxes
// against their corners' images in long double, at scales from 1e-30 to 1e25.
struct FloatCarry {
  const BvhRelation::FloatMap& to_a_map;
  const BvhRelation::FloatMap& to_b_map;

  static PEELCD_ALWAYS_INLINE FBox carry(const FBox& in, const BvhRelation::FloatMap& f) {
#if defined(__SSE__) || defined(_M_X64)
    // lo0 lo1 lo2 hi0 and lo2 hi0 hi1 hi2: both loads inside the box's six floats.
    const __m128 l4 = _mm_loadu_ps(in.lo), h4 = _mm_loadu_ps(in.lo + 2);
    const __m128 lo = l4, hi = _mm_shuffle_ps(h4, h4, _MM_SHUFFLE(3, 3, 2, 1));  // lane 3: unused
    const __m128 half_ = _mm_set1_ps(0.5f), sign = _mm_set1_ps(-0.0f);
    const __m128 c = _mm_mul_ps(_mm_add_ps(lo, hi), half_);
    const __m128 e = _mm_mul_ps(_mm_sub_ps(hi, lo), half_);
    const __m128 a = _mm_max_ps(_mm_andnot_ps(sign, lo), _mm_andnot_ps(sign, hi));
    const __m128 col0 = _mm_load_ps(f.col[0]), col1 = _mm_load_ps(f.col[1]), col2 = _mm_load_ps(f.col[2]);
    const __m128 abs0 = _mm_load_ps(f.abs_col[0]), abs1 = _mm_load_ps(f.abs_col[1]), abs2 = _mm_load_ps(f.abs_col[2]);
#define PEELCD_LANE(v, k) _mm_shuffle_ps(v, v, _MM_SHUFFLE(k, k, k, k))
    const __m128 center = _mm_add_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(col0, PEELCD_LANE(c, 0)), _mm_mul_ps(col1, PEELCD_LANE(c, 1))),
                   _mm_mul_ps(col2, PEELCD_LANE(c, 2))),
        _mm_load_ps(f.t));
    const __m128 half = _mm_add_ps(_mm_add_ps(_mm_mul_ps(abs0, PEELCD_LANE(e, 0)), _mm_mul_ps(abs1, PEELCD_LANE(e, 1))),
                                   _mm_mul_ps(abs2, PEELCD_LANE(e, 2)));
    const __m128 m = _mm_add_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(abs0, PEELCD_LANE(a, 0)), _mm_mul_ps(abs1, PEELCD_LANE(a, 1))),
                   _mm_mul_ps(abs2, PEELCD_LANE(a, 2))),
        _mm_load_ps(f.abs_t));
#undef PEELCD_LANE
    const __m128 r = _mm_add_ps(half, _mm_add_ps(_mm_mul_ps(m, _mm_set1_ps(0x1p-19f)), _mm_set1_ps(f.grow)));
    const __m128 olo = _mm_sub_ps(center, r), ohi = _mm_add_ps(center, r);
    FBox out;
    alignas(16) float x[4], y[4];
    _mm_store_ps(x, olo);
    _mm_store_ps(y, ohi);
    for (int k = 0; k < 3; ++k) out.lo[k] = x[k], out.hi[k] = y[k];
    return out;
#else
    float c[3], e[3], a[3];
    for (int j = 0; j < 3; ++j) {
      c[j] = (in.lo[j] + in.hi[j]) * 0.5f;
      e[j] = (in.hi[j] - in.lo[j]) * 0.5f;
      a[j] = std::max(std::abs(in.lo[j]), std::abs(in.hi[j]));
    }
    FBox out;
    for (int k = 0; k < 3; ++k) {
      const float center = ((f.col[0][k] * c[0] + f.col[1][k] * c[1]) + f.col[2][k] * c[2]) + f.t[k];
      const float half = (f.abs_col[0][k] * e[0] + f.abs_col[1][k] * e[1]) + f.abs_col[2][k] * e[2];
      const float m = ((f.abs_col[0][k] * a[0] + f.abs_col[1][k] * a[1]) + f.abs_col[2][k] * a[2]) + f.abs_t[k];
      const float r = half + (m * 0x1p-19f + f.grow);
      out.lo[k] = center - r;
      out.hi[k] = center + r;
    }
    return out;
#endif
  }
  PEELCD_ALWAYS_INLINE FBox to_a(const FBox& b) const { return carry(b, to_a_map); }
  PEELCD_ALWAYS_INLINE FBox to_b(const FBox& a) const { return carry(a, to_b_map); }
  // All eight lanes of `leaf` carried into B's frame at once (lanes as structure of arrays: the
  // same operations in the same order as carry(), so each lane's box equals carry()'s bit for
  // bit, in builds that do not fuse multiply-adds, as the project's do not); the lanes outside `lanes` (bits; empty lanes hold infinities) are carried as zero
  // boxes, never read by the caller.
  void leaf_to_b(const BvhLeaf& leaf, unsigned lanes, BvhLeaf& out) const {
    const BvhRelation::FloatMap& f = to_b_map;
#if defined(__SSE__) || defined(_M_X64)
    const __m128 half_ = _mm_set1_ps(0.5f), sign = _mm_set1_ps(-0.0f), fixed = _mm_set1_ps(f.grow);
    for (int h = 0; h < 2; ++h) {
      const __m128i bits = _mm_and_si128(_mm_set1_epi32(int(lanes >> (4 * h))), _mm_setr_epi32(1, 2, 4, 8));
      const __m128 valid = _mm_castsi128_ps(_mm_cmpeq_epi32(bits, _mm_setr_epi32(1, 2, 4, 8)));
      __m128 c[3], e[3], a[3];
      for (int j = 0; j < 3; ++j) {
        const __m128 lo = _mm_and_ps(valid, _mm_load_ps(leaf.lo[j] + 4 * h));
        const __m128 hi = _mm_and_ps(valid, _mm_load_ps(leaf.hi[j] + 4 * h));
        c[j] = _mm_mul_ps(_mm_add_ps(lo, hi), half_);
        e[j] = _mm_mul_ps(_mm_sub_ps(hi, lo), half_);
        a[j] = _mm_max_ps(_mm_andnot_ps(sign, lo), _mm_andnot_ps(sign, hi));
      }
      for (int k = 0; k < 3; ++k) {
        const __m128 l0 = _mm_set1_ps(f.col[0][k]), l1 = _mm_set1_ps(f.col[1][k]), l2 = _mm_set1_ps(f.col[2][k]);
        const __m128 m0 = _mm_set1_ps(f.abs_col[0][k]), m1 = _mm_set1_ps(f.abs_col[1][k]), m2 = _mm_set1_ps(f.abs_col[2][k]);
        const __m128 center = _mm_add_ps(
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(l0, c[0]), _mm_mul_ps(l1, c[1])), _mm_mul_ps(l2, c[2])), _mm_set1_ps(f.t[k]));
        const __m128 half = _mm_add_ps(_mm_add_ps(_mm_mul_ps(m0, e[0]), _mm_mul_ps(m1, e[1])), _mm_mul_ps(m2, e[2]));
        const __m128 m = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(m0, a[0]), _mm_mul_ps(m1, a[1])), _mm_mul_ps(m2, a[2])),
                                    _mm_set1_ps(f.abs_t[k]));
        const __m128 r = _mm_add_ps(half, _mm_add_ps(_mm_mul_ps(m, _mm_set1_ps(0x1p-19f)), fixed));
        _mm_store_ps(out.lo[k] + 4 * h, _mm_sub_ps(center, r));
        _mm_store_ps(out.hi[k] + 4 * h, _mm_add_ps(center, r));
      }
    }
#else
    for (std::uint32_t u = 0; u < kBvhLeafSize; ++u) out.set(u, (lanes >> u) & 1u ? carry(leaf.box(u), f) : FBox{});
#endif
  }
};

// B's tree posed against A's: each entry carries B's node box as seen from A (computed once,
// when the pair is pushed; descending into A's children keeps it). A node pair is pushed when
// the boxes overlap in A's frame (and, descending B, in B's too); a couple is reported when A's
// triangle box overlaps B's leaf in A's frame and, carried into B's frame, B's triangle box
// there (one transform per triangle of A, B's eight boxes tested at once). Boxes carried
// through a pose are boxes of boxes: some couples whose own boxes do not overlap are reported
// (the exact test decides). With rel.identity, boxes are compared as they are.
template <class Carry>
struct Posed {
  using Entry = BvhStackEntry;
  const Bvh& a;
  const Bvh& b;
  const BvhRelation& rel;
  Carry carry;
  bool admit(BvhNodePair start, Entry& e) const {
    const FBox& xa = a.nodes()[start.first].box;
    const FBox& yb = b.nodes()[start.second].box;
    e = {start.first, start.second, rel.identity ? yb : carry.to_a(yb)};
    return xa.overlaps(e.b_in_a) && (rel.identity || carry.to_b(xa).overlaps(yb));
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
    // A's lanes that reach B's leaf box in A's frame, carried into B's frame together; of
    // those, the ones whose carried box reaches B's leaf box there, each against B's eight.
    const unsigned reach = overlap_mask(e.b_in_a, la);
    if (reach == 0) return;
    BvhLeaf carried;
    carry.leaf_to_b(la, reach, carried);
    const BvhLeaf& lb = b.leaf(y);
    for (unsigned us = reach & overlap_mask(y.box, carried); us;) {
      const unsigned u = take_lane(us);
      couples_of_lane(fn, la.tri[u], lb.tri, overlap_mask(carried.box(u), lb));
    }
  }
  // A pushed pair's lines asked for ahead of its pop: both leaves' for a pair of leaves, else
  // the right child of each internal node (its left one is next to it).
  PEELCD_ALWAYS_INLINE void ask_ahead(const BvhNode& x, const BvhNode& y) const {
    if (int(x.leaf()) & int(y.leaf())) {
      prefetch_leaf(a, x), prefetch_leaf(b, y);
      return;
    }
    if (!x.leaf()) prefetch(&a.nodes()[x.first]);
    if (!y.leaf()) prefetch(&b.nodes()[y.first]);
  }
  PEELCD_ALWAYS_INLINE void descend(const Entry& e, std::vector<Entry>& stack, std::size_t& top) const {
    reserve(stack, top, 2);
    const auto& na = a.nodes();
    const auto& nb = b.nodes();
    const BvhNode& x = na[e.a];
    const BvhNode& y = nb[e.b];
    if (y.leaf() || (!x.leaf() && x.box.max_extent() >= e.b_in_a.max_extent())) {
      for (const std::uint32_t c : {e.a + 1, x.first}) {  // B's box is in A's frame either way
        if (!na[c].box.overlaps(e.b_in_a)) continue;
        stack[top++] = {c, e.b, e.b_in_a};
        ask_ahead(na[c], y);
      }
    } else if (rel.identity) {
      for (const std::uint32_t c : {e.b + 1, y.first}) {
        if (!x.box.overlaps(nb[c].box)) continue;
        stack[top++] = {e.a, c, nb[c].box};
        ask_ahead(x, nb[c]);
      }
    } else {
      const FBox x_in_b = carry.to_b(x.box);
      for (const std::uint32_t c : {e.b + 1, y.first}) {
        const FBox& cb = nb[c].box;
        if (!cb.overlaps(x_in_b)) continue;
        const FBox yb = carry.to_a(cb);
        if (!x.box.overlaps(yb)) continue;
        stack[top++] = {e.a, c, yb};
        ask_ahead(x, nb[c]);
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

// The slots of wide node `w` whose boxes overlap `box` (closed), as bits (slot i: bit i). Unused
// slots never do.
inline unsigned overlap_mask(const FBox& box, const BvhWideNode& w) {
#if defined(__SSE__) || defined(_M_X64)
  __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (int k = 0; k < 3; ++k)
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmple_ps(_mm_set1_ps(box.lo[k]), _mm_load_ps(w.hi[k])),
                                   _mm_cmple_ps(_mm_load_ps(w.lo[k]), _mm_set1_ps(box.hi[k]))));
  return unsigned(_mm_movemask_ps(ok));
#else
  unsigned mask = 0;
  for (int i = 0; i < 4; ++i) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) ok = ok && box.lo[k] <= w.hi[k][i] && w.lo[k][i] <= box.hi[k];
    mask |= unsigned(ok) << i;
  }
  return mask;
#endif
}

inline FBox slot_box(const BvhWideNode& w, unsigned i) {
  FBox b;
  for (int k = 0; k < 3; ++k) b.lo[k] = w.lo[k][i], b.hi[k] = w.hi[k][i];
  return b;
}

// A reference of the wide traversal: a wide node's index, or kBvhWideLeaf | a leaf's index.
inline bool is_leaf_ref(std::uint32_t r) { return (r & kBvhWideLeaf) != 0; }
inline std::uint32_t leaf_ref_index(std::uint32_t r) { return r & ~kBvhWideLeaf; }

// Binary node n as references into the wide view: itself (a leaf, or a wide node's), or its two
// children (an internal node at an odd depth, whose children are slots).
inline unsigned wide_refs(const Bvh& t, std::uint32_t n, std::uint32_t out[2]) {
  const auto& nodes = t.nodes();
  unsigned k = 0;
  const auto ref = [&](std::uint32_t c) { return nodes[c].leaf() ? kBvhWideLeaf | nodes[c].first : t.wide_of(c); };
  if (nodes[n].leaf() || t.wide_of(n) != kBvhWideNone) {
    out[k++] = ref(n);
  } else {
    out[k++] = ref(n + 1);
    out[k++] = ref(nodes[n].first);
  }
  return k;
}

inline const FBox& ref_box(const Bvh& t, std::uint32_t r) {
  return is_leaf_ref(r) ? t.leaf_at(leaf_ref_index(r)).bound : t.nodes()[t.wide()[r].node].box;
}

// The slots of `w` whose children are leaves (bits).
PEELCD_ALWAYS_INLINE unsigned leaf_slots(const BvhWideNode& w) {
  unsigned m = 0;
  for (unsigned k = 0; k < 4; ++k) m |= unsigned(w.child[k] != kBvhWideNone && is_leaf_ref(w.child[k])) << k;
  return m;
}

// Asks for a pushed reference's lines ahead of its pop: a wide node's two lines; a leaf's
// whole four when it is paired with a leaf (`whole`: its triangles' boxes are read next), else
// its last line (its bound, tested against the other's node).
PEELCD_ALWAYS_INLINE void ask_ahead_wide(const Bvh& t, std::uint32_t r, bool whole) {
  if (is_leaf_ref(r)) {
    const char* p = reinterpret_cast<const char*>(&t.leaf_at(leaf_ref_index(r)));
    if (whole) prefetch(p), prefetch(p + 64), prefetch(p + 128);
    prefetch(p + 192);
  } else {
    const char* p = reinterpret_cast<const char*>(&t.wide()[r]);
    prefetch(p);
    prefetch(p + 64);
  }
}

// Two trees in one frame through their wide views: a pair of wide nodes tests each of A's four
// slots against B's four at once and pushes the overlapping child pairs (both trees descend); a
// leaf against a wide node tests its box against the node's four slots; two leaves go to
// leaf_pair_couples() as in the binary traversal. The same couples as SameFrame's (the leaf
// visit decides them; the node tests only prune, on the same boxes). Returns the reference pairs
// visited.
template <class Fn>
std::size_t traverse_same_frame_wide(const Bvh& a, const Bvh& b, BvhNodePair start, std::vector<BvhNodePair>& stack,
                                     Fn& fn) {
  if (a.empty() || b.empty()) return 0;
  std::uint32_t ra[2], rb[2];
  const unsigned ka = wide_refs(a, start.first, ra), kb = wide_refs(b, start.second, rb);
  reserve(stack, 0, 64);
  std::size_t top = 0, visited = 0;
  for (unsigned i = 0; i < ka; ++i)
    for (unsigned j = 0; j < kb; ++j)
      if (ref_box(a, ra[i]).overlaps(ref_box(b, rb[j]))) stack[top++] = {ra[i], rb[j]};
  if (top == 0) return 1;
  const auto& wa = a.wide();
  const auto& wb = b.wide();
  while (top != 0) {
    const BvhNodePair e = stack[--top];
    ++visited;
    const std::uint32_t x = e.first, y = e.second;
    if (is_leaf_ref(x) && is_leaf_ref(y)) {
      const BvhLeaf& lx = a.leaf_at(leaf_ref_index(x));
      const BvhLeaf& ly = b.leaf_at(leaf_ref_index(y));
      leaf_pair_couples(lx, lx.bound, ly, ly.bound, fn);
      continue;
    }
    reserve(stack, top, 16);
    if (is_leaf_ref(x)) {
      const BvhWideNode& w = wb[y];
      for (unsigned m = overlap_mask(a.leaf_at(leaf_ref_index(x)).bound, w); m;) {
        const std::uint32_t c = w.child[take_lane(m)];
        stack[top++] = {x, c};
        ask_ahead_wide(b, c, true);
        if (is_leaf_ref(c)) ask_ahead_wide(a, x, true);
      }
    } else if (is_leaf_ref(y)) {
      const BvhWideNode& u = wa[x];
      for (unsigned m = overlap_mask(b.leaf_at(leaf_ref_index(y)).bound, u); m;) {
        const std::uint32_t c = u.child[take_lane(m)];
        stack[top++] = {c, y};
        ask_ahead_wide(a, c, true);
        if (is_leaf_ref(c)) ask_ahead_wide(b, y, true);
      }
    } else {
      const BvhWideNode& u = wa[x];
      const BvhWideNode& w = wb[y];
      for (unsigned i = 0; i < 4 && u.child[i] != kBvhWideNone; ++i) {
        unsigned m = overlap_mask(slot_box(u, i), w);
        if (m == 0) continue;
        const std::uint32_t ci = u.child[i];
        ask_ahead_wide(a, ci, (m & leaf_slots(w)) != 0);
        while (m) {
          const std::uint32_t c = w.child[take_lane(m)];
          stack[top++] = {ci, c};
          ask_ahead_wide(b, c, is_leaf_ref(ci));
        }
      }
    }
  }
  return visited;
}

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
// Boxes are carried in floats (bvh_detail::FloatCarry) where the relation and both trees'
// magnitudes allow, else in doubles: the same guarantee, a few couples more or fewer.
template <class Fn>
std::size_t bvh_traverse(const Bvh& a, const Bvh& b, const BvhRelation& rel, BvhNodePair start,
                         std::vector<BvhStackEntry>& stack, Fn&& fn) {
  const auto small = [](const Aabb& box) {
    return box.lo.cwiseAbs().maxCoeff() < BvhRelation::kFloatRange && box.hi.cwiseAbs().maxCoeff() < BvhRelation::kFloatRange;
  };
  if (!rel.identity && rel.float_ok && small(a.box()) && small(b.box()))
    return bvh_detail::traverse_pairs(
        bvh_detail::Posed<bvh_detail::FloatCarry>{a, b, rel, {rel.float_to_a, rel.float_to_b}}, a, b, start, stack, fn);
  return bvh_detail::traverse_pairs(bvh_detail::Posed<bvh_detail::DoubleCarry>{a, b, rel, {rel}}, a, b, start, stack,
                                    fn);
}

// Trees whose wide view and leaves fit this many bytes each are asked for whole before a
// traversal from their roots (Bvh::prefetch_wide()): the default scene's two 3k-triangle trees
// (122 and 141 KB) together within half of a common L2.
inline constexpr std::size_t kBvhStreamBytes = std::size_t(256) << 10;

// bvh_traverse() for two trees in one frame (BvhRelation::identity): float boxes compared as
// they are, the stack of node pairs alone, through the trees' wide views where both are fresh
// (Bvh::wide_fresh()), else their binary nodes. The same couples.
template <class Fn>
std::size_t bvh_traverse_same_frame(const Bvh& a, const Bvh& b, BvhNodePair start, std::vector<BvhNodePair>& stack,
                                    Fn&& fn) {
  if (a.wide_fresh() && b.wide_fresh()) {
    if (start == BvhNodePair{0u, 0u} && a.wide_bytes() <= kBvhStreamBytes && b.wide_bytes() <= kBvhStreamBytes) {
      a.prefetch_wide();
      b.prefetch_wide();
    }
    return bvh_detail::traverse_same_frame_wide(a, b, start, stack, fn);
  }
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
// The same under one node pair of bvh_self_split() (a node against itself, or two nodes, the
// first's subtree before the second's).
template <class Fn>
std::size_t bvh_self_traverse_apart(const Bvh& tree, const std::uint32_t* rep, BvhNodePair start,
                                    std::vector<BvhNodePair>& stack, Fn&& fn) {
  return bvh_detail::traverse_pairs(bvh_detail::Self{tree, true, rep}, tree, tree, start, stack, fn);
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
