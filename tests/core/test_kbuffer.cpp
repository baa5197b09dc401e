// The host resolve of the k-buffer (core/kbuffer.h) against layers worked out by hand from the
// rules of shaders/abuffer_resolve.comp (and docs/design.md): nearest first, strictly behind the
// previous layer, depth ties to the earlier draw, alternate objects or any object.
#include "peelcd/core/kbuffer.h"

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
    // B(0.7, order 1). Sorted: A.3 (A draws first: it wins the tie), B.3, A.5, B.7.
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
  // Texel 0: A.3 (ID 12), then A.5 (B.3 is not strictly behind A.3), then B.7.
  CHECK(r.max_layers == 3);
  CHECK(r.max_fragments == 5);  // texel 1 overflowed: it gives no layers, the host grows
  REQUIRE(layers.size() == 3);
  CHECK(layers[0][0] == bits(0.3f));
  CHECK(layers[0][1] == 12u + 1u);
  CHECK(layers[1][0] == bits(0.5f));
  CHECK(layers[1][1] == 11u + 1u);
  CHECK(layers[2][0] == bits(0.7f));
  CHECK(layers[2][1] == (kB | (21u + 1u)));
  CHECK(layers[0][4 * 1 + 1] == 0u);  // the overflowed texel
  CHECK(layers[0][4 * 2 + 1] == 0u);  // the empty texel
  CHECK(layers[0][4 * 3 + 1] == (kB | (20u + 1u)));
  CHECK(layers[1][4 * 3 + 1] == 0u);
  // A.5 -> B.7 (dz 0.2 < 0.3) is a PCS; the run start A.3 -> B.7 (dz 0.4) is tested, not close.
  CHECK(sorted(pcs) == std::vector<IdPair>{{11, 21}});
  pcs.clear();
  p.epsilon_window = 0.5f;
  f.resolve(p, pcs, nullptr);
  CHECK(sorted(pcs) == std::vector<IdPair>{{11, 21}, {12, 21}});
}

TEST_CASE("the host k-buffer resolve alternates objects (alternate peeling)", "[kbuffer]") {
  Fixture f;
  KResolveParams p;
  p.epsilon_window = 0.3f;
  std::vector<IdPair> pcs;
  std::vector<std::vector<std::uint32_t>> layers;
  SECTION("B first: B.3, A.5, B.7") {
    p.first_object = 1;
    const KResolveResult r = f.resolve(p, pcs, &layers);
    CHECK(r.max_layers == 3);
    REQUIRE(layers.size() == 3);
    CHECK(layers[0][1] == (kB | 21u));
    CHECK(layers[1][1] == 12u);
    CHECK(layers[2][1] == (kB | 22u));
    CHECK(layers[0][4 * 3 + 1] == (kB | 21u));  // texel 3's B fragment is layer 0
    CHECK(sorted(pcs) == std::vector<IdPair>{{11, 20}, {11, 21}});
  }
  SECTION("A first: A.3, then B.7 (B.3 is not strictly behind); texel 3 has no A: no layers") {
    p.first_object = 0;
    const KResolveResult r = f.resolve(p, pcs, &layers);
    CHECK(r.max_layers == 2);
    REQUIRE(layers.size() == 2);
    CHECK(layers[0][1] == 13u);
    CHECK(layers[1][1] == (kB | 22u));
    CHECK(layers[0][4 * 3 + 1] == 0u);
    CHECK(pcs.empty());  // dz 0.4 > 0.3
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
  CHECK(pcs.empty());  // 0.2 > 0.05 and no slope term
  p.slope = 1.0f;      // 0.2 < 0.05 + 1 * |0.1 - (-0.1)|
  f.resolve(p, pcs, nullptr);
  CHECK(sorted(pcs) == std::vector<IdPair>{{10, 21}});
}
