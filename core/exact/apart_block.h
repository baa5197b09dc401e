#pragma once
// Private to the exact narrow phase and the loops that feed it (narrow_phase(), the World's
// tasks, self-collision): couples of triangles gathered a block at a time, so that the first
// question of the exact test, "does one triangle lie strictly on one side of the other's
// plane?", is answered for four couples at once in SIMD lanes before any couple reaches the
// scalar test. The lanes compute the very expressions certain_plane_sides() computes (certified.h:
// the same operations in the same order, Shewchuk's bound, no fused multiply-add), so a couple
// they call apart is one the exact test would reject at its first step, and every other couple
// goes to the exact test as before: the contacts, their order and their kinds are unchanged.
#include "peelcd/core/exact/narrow_phase.h"  // KnownSides
#include "peelcd/core/pairs.h"  // TriangleCorners

#include <cstddef>
#include <cstdint>
#include <vector>

namespace peelcd::exact_detail {

class ApartBlock {
 public:
  static constexpr std::size_t kSize = 64;  // couples a block holds (at most 64: a 64-bit mask of answers)
  using Coords = double[kSize / 4][9][4];  // a block's corners of one side (below)

  std::size_t size() const { return n_; }
  bool full() const { return n_ == kSize; }
  void clear() { n_ = 0; }

  // Adds the couple of triangles (ta, tb), corners a and b, as the block's next one.
  void put(std::uint32_t ta, std::uint32_t tb, const TriangleCorners& a, const TriangleCorners& b) {
    put(ta, tb, a[0], a[1], a[2], b[0], b[1], b[2]);
  }
  void put(std::uint32_t ta, std::uint32_t tb, const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
           const Vec3& b1, const Vec3& b2) {
    const std::size_t i = n_++;
    tri_a_[i] = ta;
    tri_b_[i] = tb;
    const Vec3* c[6] = {&a0, &a1, &a2, &b0, &b1, &b2};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) {
        a_[i / 4][3 * k + d][i % 4] = (*c[k])[d];
        b_[i / 4][3 * k + d][i % 4] = (*c[3 + k])[d];
      }
  }

  // Empties the block: fn(ta, tb, a, b, sides) for each couple apart() leaves, in the order
  // they were put, `sides` holding the signs the lanes certified (ContactTest takes them instead
  // of computing them again); stops early, returning false, when fn returns false.
  template <class Fn>
  bool drain(Fn&& fn) {
    const std::size_t m = n_;
    std::uint64_t left = ~apart() & (m == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << m) - 1);
    n_ = 0;
    for (; left; left &= left - 1) {
      const std::size_t i = std::size_t(__builtin_ctzll(left));
      KnownSides sides;
      side_b_.get(i, sides.b, sides.b_known);
      side_a_.get(i, sides.a, sides.a_known);
      if (!fn(tri_a_[i], tri_b_[i], corners(a_, i), corners(b_, i), sides)) return false;
    }
    return true;
  }

  // Three corners' certified sides against a plane, couple i at bit i: above, below (neither:
  // not certified).
  struct Sides {
    std::uint64_t above[3] = {0, 0, 0}, below[3] = {0, 0, 0};
    std::uint64_t known = 0;  // all three certified
    // Couple i's signs, and whether all three are certified.
    void get(std::size_t i, std::int8_t (&side)[3], bool& all) const {
      for (int k = 0; k < 3; ++k) side[k] = std::int8_t(int(above[k] >> i & 1) - int(below[k] >> i & 1));
      all = known >> i & 1;
    }
  };

  // Bit i set: couple i is certainly apart, all of one triangle's corners strictly on one side
  // of the other's plane by signs the double evaluation certifies (either plane: A's, as the
  // exact test asks first, or B's, as it asks second). Bits at and above size() are 0. Also
  // keeps each couple's certified sides for drain(). `lanes`: the instruction set (best: AVX2
  // where the processor has it, else SSE2; the others for tests, which hold them equal).
  enum class Lanes { best, sse2, portable };
  std::uint64_t apart(Lanes lanes = Lanes::best);

 private:
  static TriangleCorners corners(const Coords& c, std::size_t i) {
    const double(&g)[9][4] = c[i / 4];
    const std::size_t l = i % 4;
    return {Vec3(g[0][l], g[1][l], g[2][l]), Vec3(g[3][l], g[4][l], g[5][l]), Vec3(g[6][l], g[7][l], g[8][l])};
  }
  // Four couples a group, by coordinate: [i / 4][3 k + d][i % 4] is corner k's coordinate d of
  // couple i (a couple's 18 numbers on a few neighbouring lines, a group's lanes together for the
  // SIMD loads). Not initialized: apart() zeroes the lanes past size() in the last group of four
  // it reads, so that they compute on finite numbers (the tests trap floating-point exceptions).
  alignas(32) Coords a_;
  alignas(32) Coords b_;
  std::uint32_t tri_a_[kSize], tri_b_[kSize];
  Sides side_b_, side_a_;  // B's corners against A's plane; A's against B's
  std::size_t n_ = 0;
};
static_assert(ApartBlock::kSize <= 64 && ApartBlock::kSize % 4 == 0, "a block's answers are one 64-bit mask, four lanes at a time");

// What most loops drain a block into: each couple left tested by `test`, its contact (its
// triangles' indices as put) appended to `out`; false, ending the drain, once `out` holds
// `limit` contacts.
struct TestInto {
  ContactTest& test;
  std::vector<Contact>& out;
  std::size_t limit = std::size_t(-1);
  bool operator()(std::uint32_t ta, std::uint32_t tb, const TriangleCorners& a, const TriangleCorners& b,
                  const KnownSides& sides) const {
    Contact contact;
    contact.tri_a = ta;
    contact.tri_b = tb;
    if (!test(a, b, contact, sides)) return true;
    out.push_back(contact);
    return out.size() < limit;
  }
};

}  // namespace peelcd::exact_detail
