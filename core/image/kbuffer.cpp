#include "peelcd/core/image/kbuffer.h"
#include "peelcd/core/image/texel.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace peelcd {
namespace {

using texel::as_float;

struct Layer {
  std::uint32_t depth = 0, key = 0, dzdx = 0, dzdy = 0;  // key: object << 31 | ID + 1
  bool operator!=(const Layer& o) const {
    return depth != o.depth || key != o.key || dzdx != o.dzdx || dzdy != o.dzdy;
  }
};

// shaders/abuffer_resolve.comp's test_pair, in the same float operations.
void test_pair(const Layer& t0, const Layer& t1, const KResolveParams& p, std::vector<IdPair>& pcs) {
  const float spread = std::fabs(as_float(t1.dzdx) - as_float(t0.dzdx)) + std::fabs(as_float(t1.dzdy) - as_float(t0.dzdy));
  if (!pcs_within_epsilon(as_float(t0.depth), as_float(t1.depth), spread, p.epsilon_window, p.slope)) return;
  const std::uint32_t id0 = (t0.key & 0x7fffffffu) - 1u, id1 = (t1.key & 0x7fffffffu) - 1u;
  const IdPair pair = (t0.key >> 31) == 0u ? IdPair{id0, id1} : IdPair{id1, id0};
  // Neighbouring texels mostly repeat the last pair: keep the list short (the caller makes it
  // unique anyway).
  if (pcs.empty() || !(pcs.back() == pair)) pcs.push_back(pair);
}

// (depth, rank << 31 | draw order) with rank = object ^ flip: the order the compute resolve picks
// fragments in. Alternate peeling ranks the first object's fragments before the other's at equal
// depth (flip = first object), full peeling object A's (flip = 0), so that of two fragments of
// different objects at the same depth both become layers (docs/design.md 1.5, ties).
bool before(const KFragment& x, const KFragment& y, std::uint32_t flip) {
  const float zx = as_float(x.depth), zy = as_float(y.depth);
  return zx < zy || (zx == zy && (x.key ^ flip) < (y.key ^ flip));
}

// Conservative mode: every fragment of the texel is a layer, in (lower depth, object, draw order)
// order; every two of different objects whose closed intervals overlap are a PCS.
void resolve_intervals(const std::vector<KFragment>& sorted, std::uint32_t n, const KResolveParams& p,
                       std::size_t texel, std::size_t texels, std::vector<IdPair>& pcs,
                       std::vector<std::vector<std::uint32_t>>* layers) {
  for (std::uint32_t i = 0; i < n; ++i) {
    const KFragment& f = sorted[i];
    const std::uint32_t object = f.key >> 31;
    if (layers) {
      if (layers->size() <= i) layers->emplace_back(texels * 4, 0u);
      std::uint32_t* out = (*layers)[i].data() + 4 * texel;
      out[0] = f.depth, out[1] = (object << 31) | (p.ids[object][f.key & 0x7fffffffu] + 1u), out[2] = f.dzdx;
      out[3] = 0u;
    }
    const float lo = as_float(f.depth), hi = as_float(f.dzdx);
    // Sorted by lower depth: the fragments after i overlap it while their lower depth is within
    // its interval (the shared test, peelcd/core/image/pcs_test.inc); the first that does not ends it.
    for (std::uint32_t j = i + 1;
         j < n && pcs_intervals_overlap(lo, hi, as_float(sorted[j].depth), as_float(sorted[j].dzdx)); ++j) {
      const std::uint32_t other = sorted[j].key >> 31;
      if (other == object) continue;
      const std::uint32_t id_i = p.ids[object][f.key & 0x7fffffffu];
      const std::uint32_t id_j = p.ids[other][sorted[j].key & 0x7fffffffu];
      const IdPair pair = object == 0u ? IdPair{id_i, id_j} : IdPair{id_j, id_i};
      if (pcs.empty() || !(pcs.back() == pair)) pcs.push_back(pair);
    }
  }
}

// Texels [first, last) of the k-buffer.
KResolveResult resolve_range(const KBuffer& kb, const KResolveParams& p, std::size_t first, std::size_t last,
                             std::vector<IdPair>& pcs, std::vector<KFragment>& sorted,
                             std::vector<std::vector<std::uint32_t>>* layers) {
  KResolveResult result;
  const std::size_t texels = std::size_t(kb.resolution) * std::size_t(kb.resolution);
  const std::size_t stride = kb.stride ? kb.stride : texels;
  if (sorted.size() < kb.slots) sorted.resize(kb.slots);
  for (std::size_t t = first; t < last; ++t) {
    const std::uint32_t n = kb.counts[t];
    if (n > kb.slots) {
      result.max_fragments = std::max(result.max_fragments, n);
      continue;  // fragments were dropped: no layers from this texel (the host peels again)
    }
    if (n == 0) continue;
    if (n == 1 && !layers) {  // one surface: layer 0 or nothing, no pair
      if (p.full_peel || p.conservative || (kb.fragments[kb.offsets ? kb.offsets[t] : t].key >> 31) == p.first_object)
        result.max_layers = std::max(result.max_layers, 1u);
      continue;
    }
    const std::uint32_t flip = p.full_peel || p.conservative ? 0u : p.first_object << 31;
    // Insertion sort: a texel holds a handful of fragments.
    for (std::uint32_t i = 0; i < n; ++i) {
      const KFragment f = kb.fragments[kb.offsets ? std::size_t(kb.offsets[t]) + i : std::size_t(i) * stride + t];
      std::uint32_t j = i;
      for (; j > 0 && before(f, sorted[j - 1], flip); --j) sorted[j] = sorted[j - 1];
      sorted[j] = f;
    }
    if (p.conservative) {
      resolve_intervals(sorted, n, p, t, texels, pcs, layers);
      result.max_layers = std::max(result.max_layers, n);
      continue;
    }
    Layer prev, run_start;
    std::uint32_t k = 0;
    for (std::uint32_t i = 0; i < n; ++k) {
      // Layer k: the first fragment (in sorted order) of the wanted object behind layer k - 1 in
      // (depth, rank) order; everything before position i is not behind it. What follows i is
      // behind it unless it has layer k - 1's depth and object (full peeling; alternate peeling
      // wants the other object, which at that depth sorts after layer k - 1 only if it ranks
      // higher).
      const std::uint32_t want = p.full_peel ? 2u : ((p.first_object + k) & 1u);
      const float prev_z = as_float(prev.depth);
      const std::uint32_t prev_object = prev.key >> 31;
      while (i < n && ((k > 0 && as_float(sorted[i].depth) == prev_z && (sorted[i].key >> 31) == prev_object) ||
                       (want != 2u && (sorted[i].key >> 31) != want)))
        ++i;
      if (i == n) break;
      const KFragment& best = sorted[i++];
      const std::uint32_t object = best.key >> 31;
      const std::uint32_t id = p.ids[object][best.key & 0x7fffffffu];
      const Layer layer{best.depth, (object << 31) | (id + 1u), best.dzdx, best.dzdy};
      if (layers) {
        if (layers->size() <= k) layers->emplace_back(texels * 4, 0u);
        std::uint32_t* out = (*layers)[k].data() + 4 * t;
        out[0] = layer.depth, out[1] = layer.key, out[2] = layer.dzdx, out[3] = layer.dzdy;
      }
      if (k > 0) {
        const bool switched = (prev.key >> 31) != (layer.key >> 31);
        if (switched) test_pair(prev, layer, p, pcs);
        if (p.full_peel) {
          if (run_start.key == 0u) run_start = prev;
          if (switched) {
            if (run_start != prev) test_pair(run_start, layer, p, pcs);
            run_start = layer;
          }
        }
      }
      prev = layer;
    }
    result.max_layers = std::max(result.max_layers, k);
  }
  return result;
}

}  // namespace

KResolveResult resolve_kbuffer(const KBuffer& kb, const KResolveParams& p, std::vector<IdPair>& pcs,
                               std::vector<KFragment>& scratch, std::vector<std::vector<std::uint32_t>>* layers) {
  return resolve_range(kb, p, 0, std::size_t(kb.resolution) * std::size_t(kb.resolution), pcs, scratch, layers);
}

KResolveResult KResolver::resolve(const KBuffer& kb, const KResolveParams& p, std::vector<IdPair>& pcs,
                                  std::vector<std::vector<std::uint32_t>>* layers) {
  const std::size_t texels = std::size_t(kb.resolution) * std::size_t(kb.resolution);
  if (layers || lanes_.size() == 1)  // a capture grows the layer images as it goes: one lane
    return resolve_range(kb, p, 0, texels, pcs, lanes_[0].scratch, layers);
  const std::size_t n = lanes_.size();
  auto job = [&](unsigned lane) {
    // Contiguous blocks of texels: lane i takes [i * texels / n, (i + 1) * texels / n).
    Lane& l = lanes_[lane];
    l.pcs.clear();
    l.result = resolve_range(kb, p, lane * texels / n, (lane + 1) * texels / n, l.pcs, l.scratch, nullptr);
  };
  pool_.run(job);
  KResolveResult result;
  for (const Lane& l : lanes_) {
    result.max_layers = std::max(result.max_layers, l.result.max_layers);
    result.max_fragments = std::max(result.max_fragments, l.result.max_fragments);
    pcs.insert(pcs.end(), l.pcs.begin(), l.pcs.end());
  }
  return result;
}

}  // namespace peelcd
