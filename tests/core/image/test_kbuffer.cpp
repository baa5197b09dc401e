// The host resolve of the k-buffer (core/image/kbuffer.h) against layers worked out by hand from the
// rules of shaders/abuffer_resolve.comp (and docs/design.md): nearest first, behind the previous
// layer in (depth, rank) order (a fragment of the other object at the same depth is behind it),
// depth ties among candidates to the lower rank and the earlier draw, alternate objects or any.
#include "peelcd/core/image/kbuffer.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>

using namespace peelcd;

namespace {

std::uint32_t bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

constexpr std::uint32_t kB = 0x80000000u;

// 2 x 2 texels, 4 slots, slot-major as shaders/abuffer.frag stores them.
struct Fixture {
  static constexpr int kRes = 2;
  static constexpr std::size_t kTexels = 4;
  std::uint32_t counts[kTexels] = {};
  KFragment fragments[4 * kTexels] = {};
  std::uint32_t ids_a[3] = {10, 11, 12};
  std::uint32_t ids_b[2] = {20, 21};

  void add(std::size_t texel, float z, std::uint32_t key, float dzdx = 0.0f) {
    const std::uint32_t s = counts[texel]++;
    if (s < 4) fragments[s * kTexels + texel] = {bits(z), key, bits(dzdx), bits(0.0f)};
  }
  Fixture() {
    // Texel 0, in draw-completion order: A(0.5, order 1), B(0.3, order 0), A(0.3, order 2),
    // B(0.7, order 1). Sorted (full peeling): A.3 (A ranks first at equal depth), B.3, A.5, B.7.
    add(0, 0.5f, 1);
    add(0, 0.3f, kB | 0);
    add(0, 0.3f, 2);
    add(0, 0.7f, kB | 1);
    // Texel 1: five fragments, one more than the slots.
    for (int i = 0; i < 5; ++i) add(1, 0.1f * float(i + 1), 0);
    // Texel 2: none. Texel 3: one fragment of B.
    add(3, 0.25f, kB | 0);
  }
  KResolveResult resolve(KResolveParams p, std::vector<IdPair>& pcs, std::vector<std::vector<std::uint32_t>>* layers) {
    KBuffer kb{counts, fragments, kRes, 4};
    p.ids[0] = ids_a;
    p.ids[1] = ids_b;
    std::vector<KFragment> scratch;
    return resolve_kbuffer(kb, p, pcs, scratch, layers);
  }
};

std::vector<IdPair> sorted(std::vector<IdPair> v) {
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

TEST_CASE("the host k-buffer resolve peels every surface in depth order (full peeling)", "[kbuffer]") {
  Fixture f;
  KResolveParams p;
  p.full_peel = true;
  p.epsilon_window = 0.3f;
  std::vector<IdPair> pcs;
  std::vector<std::vector<std::uint32_t>> layers;
  const KResolveResult r = f.resolve(p, pcs, &layers);
  // Texel 0: A.3 (ID 12), B.3 (ID 20: the same depth, the other object: behind it), A.5, B.7.
  CHECK(r.max_layers == 4);
  CHECK(r.max_fragments == 5);  // texel 1 overflowed: it gives no layers, the host grows
  REQUIRE(layers.size() == 4);
  CHECK(layers[0][0] == bits(0.3f));
  CHECK(layers[0][1] == 12u + 1u);
  CHECK(layers[1][0] == bits(0.3f));
  CHECK(layers[1][1] == (kB | (20u + 1u)));
  CHECK(layers[2][0] == bits(0.5f));
  CHECK(layers[2][1] == 11u + 1u);
  CHECK(layers[3][0] == bits(0.7f));
  CHECK(layers[3][1] == (kB | (21u + 1u)));
  CHECK(layers[0][4 * 1 + 1] == 0u);  // the overflowed texel
  CHECK(layers[0][4 * 2 + 1] == 0u);  // the empty texel
  CHECK(layers[0][4 * 3 + 1] == (kB | (20u + 1u)));
  CHECK(layers[1][4 * 3 + 1] == 0u);
  // A.3 -> B.3 (dz 0: touching surfaces), B.3 -> A.5 and A.5 -> B.7 (dz 0.2 < 0.3).
  CHECK(sorted(pcs) == std::vector<IdPair>{{11, 20}, {11, 21}, {12, 20}});
  pcs.clear();
  p.epsilon_window = 0.1f;
  f.resolve(p, pcs, nullptr);
  CHECK(sorted(pcs) == std::vector<IdPair>{{12, 20}});  // only the tie
}

TEST_CASE("the host k-buffer resolve alternates objects (alternate peeling)", "[kbuffer]") {
  Fixture f;
  KResolveParams p;
  p.epsilon_window = 0.3f;
  std::vector<IdPair> pcs;
  std::vector<std::vector<std::uint32_t>> layers;
  SECTION("B first: B.3, A.3 (the tie: A ranks after B here), B.7") {
    p.first_object = 1;
    const KResolveResult r = f.resolve(p, pcs, &layers);
    CHECK(r.max_layers == 3);
    REQUIRE(layers.size() == 3);
    CHECK(layers[0][1] == (kB | 21u));
    CHECK(layers[1][1] == 13u);
    CHECK(layers[2][1] == (kB | 22u));
    CHECK(layers[0][4 * 3 + 1] == (kB | 21u));  // texel 3's B fragment is layer 0
    CHECK(sorted(pcs) == std::vector<IdPair>{{12, 20}});  // A.3 -> B.7 is 0.4 apart
  }
  SECTION("A first: A.3, B.3 (the tie), A.5, B.7; texel 3 has no A: no layers") {
    p.first_object = 0;
    const KResolveResult r = f.resolve(p, pcs, &layers);
    CHECK(r.max_layers == 4);
    REQUIRE(layers.size() == 4);
    CHECK(layers[0][1] == 13u);
    CHECK(layers[1][1] == (kB | 21u));
    CHECK(layers[2][1] == 12u);
    CHECK(layers[3][1] == (kB | 22u));
    CHECK(layers[0][4 * 3 + 1] == 0u);
    CHECK(sorted(pcs) == std::vector<IdPair>{{11, 20}, {11, 21}, {12, 20}});
  }
}

TEST_CASE("the host k-buffer resolve follows the slopes (slope-following epsilon)", "[kbuffer]") {
  Fixture f;
  // Texel 2: A at 0.5 rising, B at 0.7 falling: planes 0.2 apart with slopes 0.1 and -0.1.
  f.add(2, 0.5f, 0, 0.1f);
  f.add(2, 0.7f, kB | 1, -0.1f);
  KResolveParams p;
  p.full_peel = true;
  p.epsilon_window = 0.05f;
  std::vector<IdPair> pcs;
  f.resolve(p, pcs, nullptr);
  CHECK(sorted(pcs) == std::vector<IdPair>{{12, 20}});  // texel 2: 0.2 > 0.05, no slope term
  pcs.clear();
  p.slope = 1.0f;  // 0.2 < 0.05 + 1 * |0.1 - (-0.1)|
  f.resolve(p, pcs, nullptr);
  CHECK(sorted(pcs) == std::vector<IdPair>{{10, 21}, {12, 20}});
}

TEST_CASE("the host k-buffer resolve of depth intervals (conservative mode)", "[kbuffer][conservative]") {
  // Fragments hold [lo, hi]: every overlapping couple of different objects is a PCS, whatever
  // lies between them; every fragment is a layer, in (lo, object, order) order.
  Fixture f;
  KResolveParams p;
  p.conservative = true;
  f.counts[0] = f.counts[1] = f.counts[3] = 0;
  const auto add = [&](std::size_t texel, float lo, float hi, std::uint32_t key) {
    const std::uint32_t s = f.counts[texel]++;
    f.fragments[s * Fixture::kTexels + texel] = {bits(lo), key, bits(hi), 0u};
  };
  add(0, 0.2f, 0.6f, 0);       // A, ID 10: overlaps B.5 and B.55 (not adjacent to the latter)
  add(0, 0.3f, 0.35f, 1);      // A, ID 11: overlaps nothing of B
  add(0, 0.5f, 0.55f, kB | 0);  // B, ID 20
  add(0, 0.6f, 0.9f, kB | 1);   // B, ID 21: touches A's [0.2, 0.6] at 0.6 (closed intervals)
  add(3, 0.1f, 0.2f, kB | 0);
  std::vector<IdPair> pcs;
  std::vector<std::vector<std::uint32_t>> layers;
  const KResolveResult r = f.resolve(p, pcs, &layers);
  CHECK(r.max_layers == 4);
  REQUIRE(layers.size() == 4);
  CHECK(layers[0][0] == bits(0.2f));
  CHECK(layers[0][1] == 11u);
  CHECK(layers[0][2] == bits(0.6f));
  CHECK(layers[1][1] == 12u);
  CHECK(layers[2][1] == (kB | 21u));
  CHECK(layers[3][1] == (kB | 22u));
  CHECK(layers[0][4 * 3 + 1] == (kB | 21u));
  CHECK(sorted(pcs) == std::vector<IdPair>{{10, 20}, {10, 21}});
}
