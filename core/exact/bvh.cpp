#include "peelcd/core/exact/bvh.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace peelcd {
namespace {

// A box's three extents summed (Bvh::growth()'s measure).
double extents(const FBox& b) { return (double(b.hi[0]) - b.lo[0]) + (double(b.hi[1]) - b.lo[1]) + (double(b.hi[2]) - b.lo[2]); }

}  // namespace

// A range of n triangles makes ceil(n / kBvhLeafSize) leaves (each split gives the left child
// whole leaves) and twice as many nodes less one: where each subtree's nodes and leaves go in
// depth-first order is known before it is built, so subtrees can be built apart.
namespace {
std::uint32_t leaves_for(std::uint32_t n) { return (n + kBvhLeafSize - 1) / kBvhLeafSize; }
std::uint32_t nodes_for(std::uint32_t n) { return 2 * leaves_for(n) - 1; }
}  // namespace

void Bvh::build(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles) {
  const std::size_t parts = plan_build(vertices, triangles, 1);
  for (std::size_t k = 0; k < parts; ++k) build_part(k);
  finish_build(triangles);
}

// The partitions move each triangle's centroid with its index (no indirection in the centroid
// box's pass or in nth_element's comparisons): the same comparisons as on indices, so the same
// order and tree, faster (a 100k-triangle build: 31-32 ms against 37-39 ms through the indices).
// order_ is written at the leaves.
std::size_t Bvh::plan_build(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles, std::size_t want) {
  const std::size_t n = triangles.size();
  nodes_.clear();
  leaves_.clear();
  wide_.clear();
  wide_of_.clear();
  slot_of_.clear();
  leaf_node_.clear();
  corners_.clear();
  parents_.clear();
  build_parts_.clear();
  build_top_.clear();
  depth_ = 0;
  size_ = size_at_build_ = 0.0;
  order_.resize(n);
  leaf_of_.resize(n);
  lane_of_.resize(n);
  box_ = Aabb{};
  std::iota(order_.begin(), order_.end(), 0u);
  vertex_boxes_.resize(vertices.size());
  unused_.clear();
  ++changes_;
  wide_fresh_ = true;  // (empty, or synced by finish_build())
  if (n == 0) return 0;
  std::vector<std::uint8_t> used(vertices.size(), 0);
  for (const Tri& f : triangles)
    for (const std::uint32_t v : f) used[v] = 1;
  if (std::find(used.begin(), used.end(), 0) != used.end()) {  // vertices no triangle uses: kept out of box()
    unused_.resize(used.size());
    for (std::size_t v = 0; v < used.size(); ++v) unused_[v] = !used[v];
  }
  build_items_.resize(n);
  build_boxes_.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    const Aabb b = triangle_bounds(vertices, triangles[t]);
    build_boxes_[t] = FBox::enclosing(b);
    const Vec3 c = b.center();
    build_items_[t] = BuildItem{{c.x(), c.y(), c.z()}, std::uint32_t(t)};
    box_.extend(b.lo);
    box_.extend(b.hi);
  }
  const std::uint32_t count = std::uint32_t(n);
  nodes_.resize(nodes_for(count));
  parents_.resize(nodes_.size());
  leaves_.resize(leaves_for(count));
  leaf_node_.resize(leaves_.size());
  leaf_first_.resize(leaves_.size());
  // Level by level from the root: each subtree of the frontier with more than one leaf is split
  // (its node joins the top, its children the frontier) while the frontier holds fewer than `want`.
  build_parts_.push_back(BuildPart{0, count, 0, 0, 0, 1, 1});
  for (bool grew = true; grew && build_parts_.size() < want;) {
    grew = false;
    const std::size_t level = build_parts_.size();
    for (std::size_t k = 0; k < level && build_parts_.size() < want; ++k) {
      const BuildPart at = build_parts_[k];
      if (at.end - at.begin <= kBvhLeafSize) continue;
      const std::uint32_t mid = split_range(at.begin, at.end);
      const std::uint32_t right = at.node + 1 + nodes_for(mid - at.begin);
      nodes_[at.node].first = right;
      nodes_[at.node].count = 0;
      parents_[at.node] = at.parent;
      build_top_.push_back(at.node);
      build_parts_[k] = BuildPart{at.begin, mid, at.node + 1, at.node, at.leaf, at.level + 1, at.level + 1};
      build_parts_.push_back(
          BuildPart{mid, at.end, right, at.node, at.leaf + leaves_for(mid - at.begin), at.level + 1, at.level + 1});
      grew = true;
    }
  }
  std::sort(build_parts_.begin(), build_parts_.end(), [](const BuildPart& a, const BuildPart& b) { return a.node < b.node; });
  std::sort(build_top_.begin(), build_top_.end(), std::greater<>());  // children before parents
  return build_parts_.size();
}

void Bvh::build_part(std::size_t k) {
  BuildPart& at = build_parts_[k];
  std::size_t depth = at.level;
  build_node(at, depth);
  at.depth = depth;
}

void Bvh::finish_build(const std::vector<Tri>& triangles) {
  const std::size_t n = triangles.size();
  if (n == 0) return;
  for (const BuildPart& at : build_parts_) depth_ = std::max(depth_, at.depth);
  for (const std::uint32_t i : build_top_) {
    FBox box = nodes_[i + 1].box;
    box.merge(nodes_[nodes_[i].first].box);
    nodes_[i].box = box;
  }
  corners_.resize(n);
  for (std::size_t k = 0; k < n; ++k) corners_[k] = triangles[order_[k]];
  dirty_.assign(nodes_.size(), 0);
  wide_of_.assign(nodes_.size(), kBvhWideNone);
  slot_of_.assign(nodes_.size(), kBvhWideNone);
  wide_.reserve(nodes_.size() / 3 + 1);
  if (!nodes_[0].leaf()) build_wide(0);
  sync_wide();
  size_ = 0.0;
  for (const BvhNode& node : nodes_)
    if (!node.leaf()) size_ += extents(node.box);
  size_at_build_ = size_;
}

// The split of a range of more than one leaf: along its centroids' widest axis, at the median
// that leaves the left child whole leaves (half of those the range needs, rounded up).
std::uint32_t Bvh::split_range(std::uint32_t begin, std::uint32_t end) {
  std::vector<BuildItem>& items = build_items_;
  double lo[3] = {items[begin].c[0], items[begin].c[1], items[begin].c[2]}, hi[3] = {lo[0], lo[1], lo[2]};
  for (std::uint32_t i = begin + 1; i < end; ++i)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], items[i].c[k]), hi[k] = std::max(hi[k], items[i].c[k]);
  int axis = 0;
  Vec3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]).maxCoeff(&axis);
  const std::uint32_t mid = begin + (leaves_for(end - begin) + 1) / 2 * kBvhLeafSize;
  // Ties broken by index: the same tree on every machine.
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                   [axis](const BuildItem& a, const BuildItem& b) {
                     const double ca = a.c[axis], cb = b.c[axis];
                     return ca < cb || (ca == cb && a.t < b.t);
                   });
  return mid;
}

void Bvh::build_node(const BuildPart& at, std::size_t& depth) {
  const std::uint32_t index = at.node, begin = at.begin, end = at.end;
  parents_[index] = at.parent;
  depth = std::max(depth, at.level);
  if (end - begin <= kBvhLeafSize) {
    BvhLeaf& leaf = leaves_[at.leaf];
    leaf = BvhLeaf{};
    const FBox empty;
    FBox box;
    for (std::uint32_t lane = 0; lane < kBvhLeafSize; ++lane) {
      const bool used = begin + lane < end;
      const std::uint32_t t = used ? build_items_[begin + lane].t : 0u;
      if (used) order_[begin + lane] = t;
      leaf.tri[lane] = t;
      leaf.set(lane, used ? build_boxes_[t] : empty);
      if (!used) continue;
      box.merge(build_boxes_[t]);
      leaf_of_[t] = index;
      lane_of_[t] = std::uint8_t(lane);
    }
    nodes_[index].box = box;
    nodes_[index].first = at.leaf;
    nodes_[index].count = end - begin;
    leaf_node_[at.leaf] = index;
    leaf_first_[at.leaf] = begin;
    return;
  }
  const std::uint32_t mid = split_range(begin, end);
  const std::uint32_t right = index + 1 + nodes_for(mid - begin);
  build_node(BuildPart{begin, mid, index + 1, index, at.leaf, at.level + 1, 0}, depth);  // the left child: index + 1
  build_node(BuildPart{mid, end, right, index, at.leaf + leaves_for(mid - begin), at.level + 1, 0}, depth);
  nodes_[index].first = right;
  nodes_[index].count = 0;
  FBox box = nodes_[index + 1].box;
  box.merge(nodes_[right].box);
  nodes_[index].box = box;
}

// Depth first, as the binary nodes: a wide node's children after it.
std::uint32_t Bvh::build_wide(std::uint32_t node) {
  const std::uint32_t w = std::uint32_t(wide_.size());
  wide_.emplace_back();
  wide_of_[node] = w;
  std::uint32_t slots[4], used = 0;
  for (const std::uint32_t c : {node + 1, nodes_[node].first}) {
    if (nodes_[c].leaf()) {
      slots[used++] = c;
    } else {
      slots[used++] = c + 1;
      slots[used++] = nodes_[c].first;
    }
  }
  for (std::uint32_t k = 0; k < 4; ++k) {
    put_slot(wide_[w], k, FBox{});  // unused slots stay empty; sync_wide() fills the others
    wide_[w].child[k] = kBvhWideNone;
  }
  wide_[w].node = node;
  for (std::uint32_t k = 0; k < used; ++k) {
    const std::uint32_t s = slots[k];
    slot_of_[s] = 4 * w + k;
    const std::uint32_t child = nodes_[s].leaf() ? (kBvhWideLeaf | nodes_[s].first) : build_wide(s);  // (wide_ may grow)
    wide_[w].child[k] = child;
  }
  return w;
}

void Bvh::prefetch_wide() const {
  const auto ask = [](const void* data, std::size_t bytes) {
    const char* c = static_cast<const char*>(data);
    for (std::size_t i = 0; i < bytes; i += 128) {  // two lines a step: both arrays are whole multiples of 128 bytes
      __builtin_prefetch(c + i);
      __builtin_prefetch(c + i + 64);
    }
  };
  static_assert(sizeof(BvhWideNode) % 128 == 0 && sizeof(BvhLeaf) % 128 == 0, "whole pairs of lines");
  ask(wide_.data(), wide_.size() * sizeof(BvhWideNode));
  ask(leaves_.data(), leaves_.size() * sizeof(BvhLeaf));
}

void Bvh::sync_wide() {
  for (BvhWideNode& w : wide_)
    for (std::uint32_t k = 0; k < 4 && w.child[k] != kBvhWideNone; ++k) {
      const std::uint32_t c = w.child[k];
      put_slot(w, k, nodes_[(c & kBvhWideLeaf) ? leaf_node_[c & ~kBvhWideLeaf] : wide_[c].node].box);
    }
  for (std::size_t l = 0; l < leaves_.size(); ++l) leaves_[l].bound = nodes_[leaf_node_[l]].box;
  wide_fresh_ = true;
}

double Bvh::merge_children(std::uint32_t i) {
  BvhNode& node = nodes_[i];
  FBox box = nodes_[i + 1].box;
  box.merge(nodes_[node.first].box);
  node.box = box;
  return extents(box);
}

void Bvh::refit_node(std::uint32_t i) {
  BvhNode& node = nodes_[i];
  FBox box;
  if (node.leaf()) {
    const BvhLeaf& leaf = leaves_[node.first];
    for (std::uint32_t lane = 0; lane < node.count; ++lane) box.merge(leaf.box(lane));
  } else {
    box = nodes_[i + 1].box;
    box.merge(nodes_[node.first].box);
  }
  node.box = box;
}

void Bvh::refit(const std::vector<Vec3>& vertices, const std::vector<Tri>&) {
  const Aabb exact = refit_vertices(vertices, 0, vertices.size());
  refit_leaves(vertices, 0, leaves_.size());
  refit_nodes(exact);
}

// Each vertex rounded outward to a float box once (a vertex is a corner of about six
// triangles), and the exact box of the vertices [begin, end) that the triangles use. With SSE2
// a vertex's three coordinates are rounded together by FBox::down()'s and up()'s formula, the
// same bits; a coordinate at or past 1e37 (or infinite) takes their scalar path. Loading
// (`Load`): each vertex checked finite first (the first that is not: `bad`, and the pass stops
// there) and copied to `copy` (when not null). Without `Round` (loading only), no vertex box is
// written.
template <bool Load, bool Round>
Aabb Bvh::round_vertices(const std::vector<Vec3>& vertices, Vec3* copy, std::size_t begin, std::size_t end,
                         std::size_t& bad) {
  Aabb exact;
  bad = end;
#if defined(__SSE2__)
  __m128d lo_xy = _mm_set1_pd(INFINITY), lo_z = lo_xy, hi_xy = _mm_set1_pd(-INFINITY), hi_z = hi_xy;
  const bool all_used = unused_.empty();
  const __m128 rel = _mm_set1_ps(2.4e-7f), tiny = _mm_set1_ps(1.2e-38f), big = _mm_set1_ps(1e37f);
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  // Past the second-level cache, a copy and the floats are streamed to memory (no line read
  // first), a copy two vertices (48 bytes, three aligned stores) at a time.
  const bool stream = Load && vertex_boxes_.size() >= 65536 && reinterpret_cast<std::uintptr_t>(copy) % 16 == 0;
  __m128d even_xy = _mm_setzero_pd(), even_z = even_xy;  // an even vertex's, waiting for its odd one
  for (std::size_t v = begin; v < end; ++v) {
    const double* p = vertices[v].data();
    const __m128d xy = _mm_loadu_pd(p), z = _mm_load_sd(p + 2);
    const __m128 f = _mm_movelh_ps(_mm_cvtpd_ps(xy), _mm_cvtpd_ps(z));  // (x, y, z, 0), nearest
    if (Load) {
      // x - x is 0 for a finite x, NaN for an infinite or NaN one.
      const __m128d d = _mm_or_pd(_mm_sub_pd(xy, xy), _mm_sub_pd(z, z));
      if (__builtin_expect(_mm_movemask_pd(_mm_cmpunord_pd(d, d)) != 0, 0)) {
        bad = v;
        break;
      }
      if (stream && copy && v % 2 == 0 && v + 1 < end) {
        even_xy = xy, even_z = z;
      } else if (stream && copy && v % 2 == 1 && v > begin) {
        double* q = copy[v - 1].data();
        _mm_stream_pd(q, even_xy);
        _mm_stream_pd(q + 2, _mm_unpacklo_pd(even_z, xy));
        _mm_stream_pd(q + 4, _mm_shuffle_pd(xy, z, 1));
      } else if (copy) {
        _mm_storeu_pd(copy[v].data(), xy);
        _mm_store_sd(copy[v].data() + 2, z);
      }
    }
    if (Round) {
      const __m128 a = _mm_and_ps(f, magnitude);
      const __m128 e = _mm_add_ps(_mm_mul_ps(a, rel), tiny);
      if (__builtin_expect(_mm_movemask_ps(_mm_cmpge_ps(a, big)) != 0, 0)) {
        for (int k = 0; k < 3; ++k) vertex_boxes_[v].lo[k] = FBox::down(p[k]), vertex_boxes_[v].hi[k] = FBox::up(p[k]);
      } else if (stream) {
        _mm_stream_ps(vertex_boxes_[v].lo, _mm_sub_ps(f, e));
        _mm_stream_ps(vertex_boxes_[v].hi, _mm_add_ps(f, e));
      } else {
        _mm_store_ps(vertex_boxes_[v].lo, _mm_sub_ps(f, e));
        _mm_store_ps(vertex_boxes_[v].hi, _mm_add_ps(f, e));
      }
    }
    if (!all_used && unused_[v]) continue;
    lo_xy = _mm_min_pd(lo_xy, xy), hi_xy = _mm_max_pd(hi_xy, xy);
    lo_z = _mm_min_sd(lo_z, z), hi_z = _mm_max_sd(hi_z, z);
  }
  if (stream) _mm_sfence();  // the streamed stores seen before the lanes join
  if (_mm_cvtsd_f64(lo_xy) <= _mm_cvtsd_f64(hi_xy)) {  // some vertex used
    alignas(16) double l[2], h[2];
    _mm_store_pd(l, lo_xy);
    _mm_store_pd(h, hi_xy);
    exact.lo = Vec3(l[0], l[1], _mm_cvtsd_f64(lo_z));
    exact.hi = Vec3(h[0], h[1], _mm_cvtsd_f64(hi_z));
  }
#else
  for (std::size_t v = begin; v < end; ++v) {
    const Vec3& p = vertices[v];
    if (Load) {
      if (!p.allFinite()) {
        bad = v;
        break;
      }
      if (copy) copy[v] = p;
    }
    if (Round)
      for (int k = 0; k < 3; ++k) vertex_boxes_[v].lo[k] = FBox::down(p[k]), vertex_boxes_[v].hi[k] = FBox::up(p[k]);
    if (!unused_.empty() && unused_[v]) continue;
    exact.lo = exact.lo.cwiseMin(p);
    exact.hi = exact.hi.cwiseMax(p);
  }
#endif
  return exact;
}

Aabb Bvh::refit_vertices(const std::vector<Vec3>& vertices, std::size_t begin, std::size_t end) {
  std::size_t bad;
  return round_vertices<false, true>(vertices, nullptr, begin, end, bad);
}

Aabb Bvh::load_vertices(const std::vector<Vec3>& vertices, Vec3* copy, std::size_t begin, std::size_t end,
                        std::size_t& bad, bool round) {
  return round ? round_vertices<true, true>(vertices, copy, begin, end, bad)
               : round_vertices<true, false>(vertices, copy, begin, end, bad);
}

// Each lane's box from its corners' vertex boxes (min and max of floats: no rounding), the
// leaf's box their union; the corners read in leaf order (corners_). With SSE2, four lanes at a
// time: their boxes as rows, transposed into the leaf's lanes (lanes past the count get the
// empty box). Without it, from the doubles (`vertices`) by FBox::down() and up().
void Bvh::refit_leaves(const std::vector<Vec3>& vertices, std::size_t begin, std::size_t end) {
#if defined(__SSE2__)
  (void)vertices;  // the vertex boxes of refit_vertices() hold them
  const __m128 inf = _mm_set1_ps(INFINITY), ninf = _mm_set1_ps(-INFINITY);
  // Past the second-level cache (65,536 vertices), the corners' boxes of the leaf kAhead on
  // are asked for ahead (about a tenth off a large mesh's leaves; on a small mesh, whose boxes
  // are cached anyway, the hints only cost).
  constexpr std::size_t kAhead = 4;
  const bool far = vertex_boxes_.size() >= 65536;
  for (std::size_t l = begin; l < end; ++l) {
    if (far && l + kAhead < end) {
      const std::uint32_t first = leaf_first_[l + kAhead], count = nodes_[leaf_node_[l + kAhead]].count;
      for (std::uint32_t i = 0; i < count; ++i) {
        const Tri& f = corners_[first + i];
        __builtin_prefetch(&vertex_boxes_[f[0]]);
        __builtin_prefetch(&vertex_boxes_[f[1]]);
        __builtin_prefetch(&vertex_boxes_[f[2]]);
      }
    }
    BvhLeaf& leaf = leaves_[l];
    BvhNode& node = nodes_[leaf_node_[l]];
    const Tri* corners = corners_.data() + leaf_first_[l];
    __m128 box_lo = inf, box_hi = ninf;
    for (std::uint32_t h = 0; h < kBvhLeafSize; h += 4) {
      __m128 lo[4], hi[4];
      for (std::uint32_t i = 0; i < 4; ++i) {
        if (h + i < node.count) {
          const Tri& f = corners[h + i];
          const VertexBox &p = vertex_boxes_[f[0]], &q = vertex_boxes_[f[1]], &r = vertex_boxes_[f[2]];
          lo[i] = _mm_min_ps(_mm_min_ps(_mm_load_ps(p.lo), _mm_load_ps(q.lo)), _mm_load_ps(r.lo));
          hi[i] = _mm_max_ps(_mm_max_ps(_mm_load_ps(p.hi), _mm_load_ps(q.hi)), _mm_load_ps(r.hi));
          box_lo = _mm_min_ps(box_lo, lo[i]);
          box_hi = _mm_max_ps(box_hi, hi[i]);
        } else {
          lo[i] = inf, hi[i] = ninf;
        }
      }
      _MM_TRANSPOSE4_PS(lo[0], lo[1], lo[2], lo[3]);
      _MM_TRANSPOSE4_PS(hi[0], hi[1], hi[2], hi[3]);
      if (far) {
        for (int k = 0; k < 3; ++k) {
          _mm_stream_ps(leaf.lo[k] + h, lo[k]);
          _mm_stream_ps(leaf.hi[k] + h, hi[k]);
        }
      } else {
        for (int k = 0; k < 3; ++k) {
          _mm_store_ps(leaf.lo[k] + h, lo[k]);
          _mm_store_ps(leaf.hi[k] + h, hi[k]);
        }
      }
    }
    alignas(16) float blo[4], bhi[4];
    _mm_store_ps(blo, box_lo);
    _mm_store_ps(bhi, box_hi);
    for (int k = 0; k < 3; ++k) node.box.lo[k] = blo[k], node.box.hi[k] = bhi[k];
  }
  if (far) _mm_sfence();  // the streamed boxes seen before the lanes join
#else
  for (std::size_t l = begin; l < end; ++l) {
    BvhLeaf& leaf = leaves_[l];
    BvhNode& node = nodes_[leaf_node_[l]];
    FBox box;
    for (std::uint32_t lane = 0; lane < node.count; ++lane) {
      const Tri& f = corners_[leaf_first_[l] + lane];
      FBox b;
      for (int k = 0; k < 3; ++k) {
        b.lo[k] = std::min({FBox::down(vertices[f[0]][k]), FBox::down(vertices[f[1]][k]), FBox::down(vertices[f[2]][k])});
        b.hi[k] = std::max({FBox::up(vertices[f[0]][k]), FBox::up(vertices[f[1]][k]), FBox::up(vertices[f[2]][k])});
      }
      leaf.set(lane, b);
      box.merge(b);
    }
    node.box = box;
  }
#endif
}

void Bvh::refit_nodes(const Aabb& exact) {
  box_ = exact;
  // Children follow their parents: one sweep from the last node refits bottom-up (the leaves'
  // boxes are refit_leaves()').
  double size = 0.0;
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    if (!nodes_[i].leaf()) size += merge_children(std::uint32_t(i));
  }
  size_ = size;
  wide_fresh_ = false;
  ++changes_;
}

// Level by level from the root: each internal node of the frontier gives way to its children
// (and joins the top) while the frontier holds fewer than `want`.
std::size_t Bvh::plan_parts(std::size_t want) {
  part_roots_.clear();
  part_top_.clear();
  if (nodes_.empty()) return 0;
  part_roots_.push_back(0);
  for (bool grew = true; grew && part_roots_.size() < want;) {  // a level at a time
    grew = false;
    const std::size_t level = part_roots_.size();
    for (std::size_t k = 0; k < level && part_roots_.size() < want; ++k) {
      const std::uint32_t n = part_roots_[k];
      if (nodes_[n].leaf()) continue;
      part_top_.push_back(n);
      part_roots_[k] = n + 1;  // (its place taken by its first child; the other goes last)
      part_roots_.push_back(nodes_[n].first);
      grew = true;
    }
  }
  std::sort(part_roots_.begin(), part_roots_.end());
  std::sort(part_top_.begin(), part_top_.end(), std::greater<>());
  part_sizes_.assign(part_roots_.size(), 0.0);
  return part_roots_.size();
}

// A subtree is the nodes from its root to the last leaf of its rightmost path (depth-first
// order, the second child's subtree last): swept from the back, children before parents.
void Bvh::refit_part(std::size_t k) {
  const std::uint32_t root = part_roots_[k];
  std::uint32_t end = root;
  while (!nodes_[end].leaf()) end = nodes_[end].first;
  double size = 0.0;
  for (std::size_t i = end + 1; i-- > root;) {
    if (!nodes_[i].leaf()) size += merge_children(std::uint32_t(i));
  }
  part_sizes_[k] = size;
}

void Bvh::refit_top(const Aabb& exact) {
  box_ = exact;
  double size = 0.0;
  for (const double s : part_sizes_) size += s;
  for (const std::uint32_t i : part_top_) size += merge_children(i);  // (descending: children first)
  size_ = size;
  wide_fresh_ = false;
  ++changes_;
}

void Bvh::refit(const std::vector<Vec3>& vertices, const std::vector<Tri>& triangles,
                const std::vector<std::uint32_t>& changed) {
  if (nodes_.empty()) return;
  stack_.clear();
  // The exact root box: grown by the changed triangles' new boxes; made again from every
  // triangle when a changed one's old box reached its boundary (it may shrink).
  bool recompute = false;
  for (const std::uint32_t t : changed) {
    BvhLeaf& leaf = leaves_[nodes_[leaf_of_[t]].first];
    const FBox old = leaf.box(lane_of_[t]);
    for (int k = 0; k < 3; ++k)
      if (double(old.lo[k]) <= box_.lo[k] || double(old.hi[k]) >= box_.hi[k]) recompute = true;
    const Aabb b = triangle_bounds(vertices, triangles[t]);
    leaf.set(lane_of_[t], FBox::enclosing(b));
    box_.extend(b.lo);
    box_.extend(b.hi);
    // Mark the leaf and its ancestors once; collect them.
    for (std::uint32_t n = leaf_of_[t];; n = parents_[n]) {
      if (dirty_[n]) break;
      dirty_[n] = 1;
      stack_.push_back(n);
      if (n == 0) break;
    }
  }
  // Deepest first: nodes in depth-first order have larger indices than their ancestors.
  std::sort(stack_.begin(), stack_.end(), std::greater<>());
  for (const std::uint32_t n : stack_) {
    refit_node(n);
    if (wide_fresh_) set_slot(n);
    dirty_[n] = 0;
  }
  ++changes_;
  if (recompute) {
    box_ = Aabb{};
    for (const Tri& f : triangles)
      for (const std::uint32_t v : f) box_.extend(vertices[v]);
  }
}

void Bvh::query(const Aabb& box, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (nodes_.empty()) return;
  // At most one pending sibling per level, and the root: a fixed stack for any tree this deep.
  constexpr std::size_t kFixed = 128;
  std::uint32_t fixed[kFixed];
  std::vector<std::uint32_t> grown;
  std::uint32_t* stack = fixed;
  if (depth_ + 2 > kFixed) {
    grown.resize(depth_ + 2);
    stack = grown.data();
  }
  std::size_t top = 0;
  stack[top++] = 0;
  while (top) {
    const std::uint32_t i = stack[--top];
    const BvhNode& node = nodes_[i];
    if (!node.box.overlaps(box)) continue;
    if (node.leaf()) {
      const BvhLeaf& leaf = leaves_[node.first];
      for (std::uint32_t lane = 0; lane < node.count; ++lane)
        if (leaf.box(lane).overlaps(box)) out.push_back(leaf.tri[lane]);
    } else {
      stack[top++] = node.first;
      stack[top++] = i + 1;
    }
  }
  std::sort(out.begin(), out.end());
}

BvhRelation BvhRelation::between(const Eigen::Affine3d& pose_a, const Eigen::Affine3d& pose_b) {
  BvhRelation r;
  const Eigen::Affine3d rel = pose_a.inverse(Eigen::Affine) * pose_b;
  r.identity = rel.matrix() == Eigen::Matrix4d::Identity();
  r.linear = rel.linear();
  r.abs_linear = r.linear.cwiseAbs();
  r.translation = rel.translation();
  const Eigen::Affine3d inv = pose_b.inverse(Eigen::Affine) * pose_a;
  r.inv_linear = inv.linear();
  r.inv_abs_linear = r.inv_linear.cwiseAbs();
  r.inv_translation = inv.translation();
  // World coordinates are pose * vertex: their rounding scales with the translations and with
  // the linear parts' size times the vertices' (the latter covered by the boxes' own magnitude,
  // up to the linear parts' norms, folded in here).
  r.reach = std::max(pose_a.translation().cwiseAbs().maxCoeff(), pose_b.translation().cwiseAbs().maxCoeff()) *
            std::max({1.0, r.abs_linear.maxCoeff(), r.inv_abs_linear.maxCoeff()});
  // The float maps (only where every entry is a normal float or zero, so that each rounds to
  // within 2^-24 of itself, and no product or sum of the traversal can overflow).
  const auto entry_ok = [](double v) {
    const double m = std::abs(v);
    return m == 0.0 || (m >= double(std::numeric_limits<float>::min()) && m <= 1e6);
  };
  const auto fill = [&](BvhRelation::FloatMap& f, const Eigen::Matrix3d& l, const Vec3& t) {
    bool ok = std::abs(t.x()) < kFloatRange && std::abs(t.y()) < kFloatRange && std::abs(t.z()) < kFloatRange;
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        ok = ok && entry_ok(l(k, j));
        f.col[j][k] = float(l(k, j));
        f.abs_col[j][k] = std::abs(f.col[j][k]);
      }
      f.col[j][3] = f.abs_col[j][3] = 0.0f;
      f.t[j] = float(t[j]);
      f.abs_t[j] = std::abs(f.t[j]);
    }
    f.t[3] = f.abs_t[3] = 0.0f;
    f.grow = FBox::up(1e-9 * r.reach) + 1e-37f;
    return ok;
  };
  const bool to_a_ok = fill(r.float_to_a, r.linear, r.translation);
  const bool to_b_ok = fill(r.float_to_b, r.inv_linear, r.inv_translation);
  r.float_ok = to_a_ok && to_b_ok && r.reach < kFloatRange;
  return r;
}

namespace {

// The node pairs under two nodes i (x) and j (y), not both leaves, for a split's next level: an
// internal node gives its two children, both internal their four pairs.
void split_pair(std::uint32_t i, const BvhNode& x, std::uint32_t j, const BvhNode& y, std::vector<BvhNodePair>& next) {
  if (x.leaf()) {
    next.emplace_back(i, j + 1), next.emplace_back(i, y.first);
  } else if (y.leaf()) {
    next.emplace_back(i + 1, j), next.emplace_back(x.first, j);
  } else {
    for (const std::uint32_t ci : {i + 1, x.first})
      for (const std::uint32_t cj : {j + 1, y.first}) next.emplace_back(ci, cj);
  }
}

}  // namespace

void bvh_split(const Bvh& a, const Bvh& b, const BvhRelation& rel, std::size_t tasks,
               std::vector<BvhNodePair>& out) {
  BvhSplitScratch scratch;
  bvh_split(a, b, rel, tasks, out, scratch);
}

void bvh_split(const Bvh& a, const Bvh& b, const BvhRelation& rel, std::size_t tasks,
               std::vector<BvhNodePair>& out, BvhSplitScratch& scratch) {
  out.clear();
  if (a.empty() || b.empty()) return;
  std::vector<BvhNodePair>& level = scratch.level;
  std::vector<BvhNodePair>& next = scratch.next;
  level.assign(1, BvhNodePair{0u, 0u});
  const auto& na = a.nodes();
  const auto& nb = b.nodes();
  while (!level.empty() && out.size() + level.size() < tasks) {
    next.clear();
    for (const auto& [i, j] : level) {
      const BvhNode& x = na[i];
      const BvhNode& y = nb[j];
      if (!rel.overlap(x.box.aabb(), rel.to_a(y.box.aabb()), y.box.aabb())) continue;
      if (x.leaf() && y.leaf())
        out.emplace_back(i, j);
      else
        split_pair(i, x, j, y, next);
    }
    level.swap(next);
  }
  out.insert(out.end(), level.begin(), level.end());
}

void bvh_self_split(const Bvh& tree, std::size_t tasks, std::vector<BvhNodePair>& out, BvhSplitScratch& scratch) {
  out.clear();
  if (tree.empty()) return;
  std::vector<BvhNodePair>& level = scratch.level;
  std::vector<BvhNodePair>& next = scratch.next;
  level.assign(1, BvhNodePair{0u, 0u});
  const auto& n = tree.nodes();
  while (!level.empty() && out.size() + level.size() < tasks) {
    next.clear();
    for (const auto& [i, j] : level) {
      const BvhNode& x = n[i];
      const BvhNode& y = n[j];
      if (i == j) {
        if (x.leaf()) {
          out.emplace_back(i, i);
          continue;
        }
        const std::uint32_t l = i + 1, r = x.first;
        next.emplace_back(l, l), next.emplace_back(r, r);
        if (n[l].box.overlaps(n[r].box)) next.emplace_back(l, r);
        continue;
      }
      if (!x.box.overlaps(y.box)) continue;
      if (x.leaf() && y.leaf())
        out.emplace_back(i, j);
      else
        split_pair(i, x, j, y, next);
    }
    level.swap(next);
  }
  out.insert(out.end(), level.begin(), level.end());
}

}  // namespace peelcd
