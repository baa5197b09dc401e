#pragma once
// Private to core/: the one least-significant-digit radix sort of 64-bit keys (the narrow
// phase's contact sort, the PCS expansion's sort of triangle pairs).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace peelcd::detail {

// Bits needed for `v` (0 for 0).
inline int bit_width(std::uint64_t v) {
  int bits = 0;
  for (; v; v >>= 1) ++bits;
  return bits;
}

// Sorts `keys` by their bits [first_bit, end_bit), stably (keys equal there keep their order):
// one counting pass per 11-bit digit, least significant first; `spare` is scratch (grown). A
// digit of 11 bits keeps the histogram (2,048 counters) in the first-level cache; callers take
// this sort from about 512 keys up, below which the histograms cost more than a comparison sort.
inline void radix_sort_bits(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& spare, int first_bit,
                            int end_bit) {
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t(1) << kDigit;
  spare.resize(keys.size());
  std::size_t count[kBuckets];
  for (int shift = first_bit; shift < end_bit; shift += kDigit) {
    std::fill(count, count + kBuckets, std::size_t(0));
    for (const std::uint64_t k : keys) ++count[(k >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& c : count) {
      const std::size_t n = c;
      c = sum;
      sum += n;
    }
    for (const std::uint64_t k : keys) spare[count[(k >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(spare);
  }
}

}  // namespace peelcd::detail
