#pragma once
// Private to core/: the one least-significant-digit radix sort of 64-bit keys (the narrow
// phase's contact sort, the PCS expansion's sort of triangle pairs).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace peelcd::detail {

// Bits needed for `v` (0 for 0).
inline int bit_width(std::uint64_t v) {
  int bits = 0;
  for (; v; v >>= 1) ++bits;
  return bits;
}

// Sorts `keys` by their bits [first_bit, end_bit), stably (keys equal there keep their order):
// one counting pass per digit, least significant first; `spare` is scratch (grown). A digit is
// 8 bits below kRadixWideFrom keys (256 counters: a short list pays little for its histograms)
// and 11 bits from there (2,048 counters, still in the first-level cache, fewer passes over a
// long list). A digit every key shares is skipped (its pass would move nothing). Below
// kRadixFrom keys a comparison sort is cheaper: callers sort those with std::sort.
constexpr std::size_t kRadixFrom = 32;
constexpr std::size_t kRadixWideFrom = 2048;
template <int kDigit>
inline void radix_sort_digits(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& spare, int first_bit,
                              int end_bit) {
  constexpr std::size_t kBuckets = std::size_t(1) << kDigit;
  const std::size_t n = keys.size();
  if (n == 0) return;
  spare.resize(n);
  using Count = std::conditional_t<kDigit == 8, std::uint32_t, std::size_t>;  // 8 bits: below 2,048 keys
  Count count[kBuckets];
  for (int shift = first_bit; shift < end_bit; shift += kDigit) {
    std::fill(count, count + kBuckets, Count(0));
    for (const std::uint64_t k : keys) ++count[(k >> shift) & (kBuckets - 1)];
    if (count[(keys[0] >> shift) & (kBuckets - 1)] == n) continue;  // one digit for all
    Count sum = 0;
    for (Count& c : count) {
      const Count m = c;
      c = sum;
      sum += m;
    }
    for (const std::uint64_t k : keys) spare[count[(k >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(spare);
  }
}

inline void radix_sort_bits(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& spare, int first_bit,
                            int end_bit) {
  if (keys.size() < kRadixWideFrom)
    radix_sort_digits<8>(keys, spare, first_bit, end_bit);
  else
    radix_sort_digits<11>(keys, spare, first_bit, end_bit);
}

}  // namespace peelcd::detail
