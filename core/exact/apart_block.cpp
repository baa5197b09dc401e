// The planes' test of a block of couples in SIMD lanes (apart_block.h): four couples a step, in
// 256-bit registers where the processor has AVX2 (chosen once at run time), else as two 128-bit
// halves (SSE2, every x86-64). Either way each lane computes certain_plane_sides()'s expressions
// (certified.h) in its order: the answers do not depend on the instruction set.
#include "apart_block.h"

#include "certified.h"

#include <cstring>

// The helpers below take and return 256-bit vectors; they are always inlined (no call passes
// one, so the ABI note GCC gives for them does not apply).
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace peelcd::exact_detail {
namespace {

typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));

PEELCD_ALWAYS_INLINE V4 load(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
PEELCD_ALWAYS_INLINE V4 abs4(V4 v) {
  const M4 magnitude = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL};
  return (V4)((M4)v & magnitude);
}
PEELCD_ALWAYS_INLINE V4 splat(double d) { return V4{d, d, d, d}; }

// The sides of `t`'s corners against the plane of `p`, four couples at once, as
// certain_plane_sides(p, t) computes them in its first loop: side[k] is +1, -1 or 0 (not
// certified) per lane; `certain` has the lanes whose three sides are certified, `one` those
// whose three lie strictly on one side (all ones per lane).
PEELCD_ALWAYS_INLINE void plane_sides(const double (&p)[9][ApartBlock::kSize], const double (&t)[9][ApartBlock::kSize],
                                      std::size_t i, M4 (&side)[3], M4& certain, M4& one) {
  const V4 px = load(&p[0][i]), py = load(&p[1][i]), pz = load(&p[2][i]);
  const V4 e1x = load(&p[3][i]) - px, e1y = load(&p[4][i]) - py, e1z = load(&p[5][i]) - pz;
  const V4 e2x = load(&p[6][i]) - px, e2y = load(&p[7][i]) - py, e2z = load(&p[8][i]) - pz;
  const V4 cx = e1y * e2z - e1z * e2y, cy = e1z * e2x - e1x * e2z, cz = e1x * e2y - e1y * e2x;
  const V4 mx = abs4(e1y * e2z) + abs4(e1z * e2y), my = abs4(e1z * e2x) + abs4(e1x * e2z),
           mz = abs4(e1x * e2y) + abs4(e1y * e2x);
  M4 all_above = ~M4{}, all_below = ~M4{};
  certain = ~M4{};
  for (int k = 0; k < 3; ++k) {
    const V4 fx = load(&t[3 * k][i]) - px, fy = load(&t[3 * k + 1][i]) - py, fz = load(&t[3 * k + 2][i]) - pz;
    const V4 det = fx * cx + fy * cy + fz * cz;
    const V4 bound = splat(kOrient3dBound) * (abs4(fx) * mx + abs4(fy) * my + abs4(fz) * mz) + splat(kUnderflowSlack);
    const M4 above = (M4)(det > bound), below = (M4)(det < -bound);
    side[k] = below - above;  // true is -1 in a lane: +1 above, -1 below, 0 neither
    all_above &= above;
    all_below &= below;
    certain &= above | below;
  }
  one = all_above | all_below;
}

// The block's answers: apart bits returned; the certified sides and which lanes have them.
PEELCD_ALWAYS_INLINE std::uint64_t apart_lanes(const double (&a)[9][ApartBlock::kSize],
                                               const double (&b)[9][ApartBlock::kSize], std::size_t n,
                                               std::int8_t (&side_b)[3][ApartBlock::kSize],
                                               std::int8_t (&side_a)[3][ApartBlock::kSize], std::uint64_t& known_b,
                                               std::uint64_t& known_a) {
  std::uint64_t bits = 0, kb = 0, ka = 0;
  for (std::size_t i = 0; i < n; i += 4) {
    M4 sb[3], sa[3], certain_b, certain_a, one_b, one_a;
    plane_sides(a, b, i, sb, certain_b, one_b);  // B's corners against A's plane (asked first)
    plane_sides(b, a, i, sa, certain_a, one_a);  // A's against B's
    const M4 apart = one_b | one_a;
    for (int j = 0; j < 4; ++j) {
      bits |= std::uint64_t(apart[j] != 0) << (i + j);
      kb |= std::uint64_t(certain_b[j] != 0) << (i + j);
      ka |= std::uint64_t(certain_a[j] != 0) << (i + j);
      for (int k = 0; k < 3; ++k) {
        side_b[k][i + j] = std::int8_t(sb[k][j]);
        side_a[k][i + j] = std::int8_t(sa[k][j]);
      }
    }
  }
  known_b = kb;
  known_a = ka;
  return n == ApartBlock::kSize ? bits : bits & ((std::uint64_t(1) << n) - 1);
}

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2"))) std::uint64_t apart_avx2(const double (&a)[9][ApartBlock::kSize],
                                                         const double (&b)[9][ApartBlock::kSize], std::size_t n,
                                                         std::int8_t (&side_b)[3][ApartBlock::kSize],
                                                         std::int8_t (&side_a)[3][ApartBlock::kSize],
                                                         std::uint64_t& known_b, std::uint64_t& known_a) {
  return apart_lanes(a, b, n, side_b, side_a, known_b, known_a);
}
const bool kHasAvx2 = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0;
}();
#endif

}  // namespace

std::uint64_t ApartBlock::apart() {
  for (std::size_t i = n_; i % 4 != 0; ++i)
    for (int c = 0; c < 9; ++c) a_[c][i] = b_[c][i] = 0.0;
#if defined(__x86_64__) && defined(__GNUC__)
  if (kHasAvx2) return apart_avx2(a_, b_, n_, side_b_, side_a_, known_b_, known_a_);
#endif
  return apart_lanes(a_, b_, n_, side_b_, side_a_, known_b_, known_a_);
}

}  // namespace peelcd::exact_detail
