// The planes' test of a block of couples in SIMD lanes (apart_block.h): four couples a step, in
// 256-bit registers where the processor has AVX2 (chosen once at run time), else as two 128-bit
// halves (SSE2, every x86-64). Either way each lane computes certain_plane_sides()'s expressions
// (certified.h) in its order: the answers do not depend on the instruction set.
#include "apart_block.h"

#include "certified.h"

#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

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
PEELCD_ALWAYS_INLINE V4 abs4(const V4& v) {
  const M4 magnitude = {0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL, 0x7fffffffffffffffLL};
  return (V4)((M4)v & magnitude);
}
PEELCD_ALWAYS_INLINE V4 splat(double d) { return V4{d, d, d, d}; }

// The sides of `t`'s corners against the plane of `p`, four couples at once, as
// certain_plane_sides(p, t) computes them in its first loop: above[k] and below[k] per lane
// (all ones where certified so), `one` where all three lie strictly on one side.
PEELCD_ALWAYS_INLINE void plane_sides(const ApartBlock::Coords& pb, const ApartBlock::Coords& tb, std::size_t i,
                                      M4 (&above)[3], M4 (&below)[3], M4& one) {
  const double(&p)[9][4] = pb[i / 4];
  const double(&t)[9][4] = tb[i / 4];
  const V4 px = load(p[0]), py = load(p[1]), pz = load(p[2]);
  const V4 e1x = load(p[3]) - px, e1y = load(p[4]) - py, e1z = load(p[5]) - pz;
  const V4 e2x = load(p[6]) - px, e2y = load(p[7]) - py, e2z = load(p[8]) - pz;
  const V4 cx = e1y * e2z - e1z * e2y, cy = e1z * e2x - e1x * e2z, cz = e1x * e2y - e1y * e2x;
  const V4 mx = abs4(e1y * e2z) + abs4(e1z * e2y), my = abs4(e1z * e2x) + abs4(e1x * e2z),
           mz = abs4(e1x * e2y) + abs4(e1y * e2x);
  for (int k = 0; k < 3; ++k) {
    const V4 fx = load(t[3 * k]) - px, fy = load(t[3 * k + 1]) - py, fz = load(t[3 * k + 2]) - pz;
    const V4 det = fx * cx + fy * cy + fz * cz;
    const V4 bound = splat(kOrient3dBound) * (abs4(fx) * mx + abs4(fy) * my + abs4(fz) * mz) + splat(kUnderflowSlack);
    above[k] = (M4)(det > bound);
    below[k] = (M4)(det < -bound);
  }
  one = (above[0] & above[1] & above[2]) | (below[0] & below[1] & below[2]);
}

// The block's answers as bits, lane i of the block at bit i: what apart() returns, and each
// corner's certified sides (ApartBlock::Sides). Mask turns four lanes into four bits.
template <class Mask>
PEELCD_ALWAYS_INLINE std::uint64_t apart_lanes(const ApartBlock::Coords& a, const ApartBlock::Coords& b, std::size_t n,
                                               ApartBlock::Sides& side_b, ApartBlock::Sides& side_a, Mask mask) {
  std::uint64_t bits = 0;
  side_b = side_a = ApartBlock::Sides{};
  for (std::size_t i = 0; i < n; i += 4) {
    M4 ab[3], bb[3], aa[3], ba[3], one_b, one_a;
    plane_sides(a, b, i, ab, bb, one_b);  // B's corners against A's plane (asked first)
    plane_sides(b, a, i, aa, ba, one_a);  // A's against B's
    bits |= std::uint64_t(mask(one_b | one_a)) << i;
    side_b.known |= std::uint64_t(mask((ab[0] | bb[0]) & (ab[1] | bb[1]) & (ab[2] | bb[2]))) << i;
    side_a.known |= std::uint64_t(mask((aa[0] | ba[0]) & (aa[1] | ba[1]) & (aa[2] | ba[2]))) << i;
    for (int k = 0; k < 3; ++k) {
      side_b.above[k] |= std::uint64_t(mask(ab[k])) << i;
      side_b.below[k] |= std::uint64_t(mask(bb[k])) << i;
      side_a.above[k] |= std::uint64_t(mask(aa[k])) << i;
      side_a.below[k] |= std::uint64_t(mask(ba[k])) << i;
    }
  }
  return n == 64 ? bits : bits & ((std::uint64_t(1) << n) - 1);
}

// Four lanes' signs (all ones or zero) as four bits, lane j at bit j.
struct PortableMask {
  unsigned operator()(const M4& m) const {
    return unsigned(m[0] != 0) | unsigned(m[1] != 0) << 1 | unsigned(m[2] != 0) << 2 | unsigned(m[3] != 0) << 3;
  }
};

#if defined(__x86_64__) && defined(__GNUC__)
struct SseMask {  // two 128-bit halves (SSE2: every x86-64)
  PEELCD_ALWAYS_INLINE unsigned operator()(const M4& m) const {
    __m128d lo, hi;
    std::memcpy(&lo, &m, sizeof lo);
    std::memcpy(&hi, reinterpret_cast<const char*>(&m) + sizeof lo, sizeof hi);
    return unsigned(_mm_movemask_pd(lo)) | unsigned(_mm_movemask_pd(hi)) << 2;
  }
};
struct Avx2Mask {
  __attribute__((target("avx2"))) unsigned operator()(const M4& m) const {
    return unsigned(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
  }
};
__attribute__((target("avx2"))) std::uint64_t apart_avx2(const ApartBlock::Coords& a, const ApartBlock::Coords& b,
                                                         std::size_t n,
                                                         ApartBlock::Sides& side_b, ApartBlock::Sides& side_a) {
  return apart_lanes(a, b, n, side_b, side_a, Avx2Mask{});
}
const bool kHasAvx2 = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0;
}();
#endif

}  // namespace

std::uint64_t ApartBlock::apart(Lanes lanes) {
  for (std::size_t i = n_; i % 4 != 0; ++i)
    for (int c = 0; c < 9; ++c) a_[i / 4][c][i % 4] = b_[i / 4][c][i % 4] = 0.0;
#if defined(__x86_64__) && defined(__GNUC__)
  if (lanes == Lanes::best && kHasAvx2) return apart_avx2(a_, b_, n_, side_b_, side_a_);
  if (lanes != Lanes::portable) return apart_lanes(a_, b_, n_, side_b_, side_a_, SseMask{});
#endif
  return apart_lanes(a_, b_, n_, side_b_, side_a_, PortableMask{});
}

}  // namespace peelcd::exact_detail
