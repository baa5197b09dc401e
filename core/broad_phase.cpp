#include "peelcd/core/broad_phase.h"

#include "radix_sort.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {

std::vector<std::pair<std::size_t, std::size_t>> overlapping_pairs(const std::vector<Aabb>& boxes) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  SweepScratch scratch;
  overlapping_pairs(boxes, out, scratch);
  return out;
}

// The non-empty boxes sorted by their lower x, their bounds copied in that order into one array
// per bound (the sweep reads six doubles a box, in a row); each box then against those after it
// in the order whose lower x is at most its upper x (their x ranges overlap: the order gives
// lo_x[i] <= lo_x[j]), their y and z ranges compared without a branch, the pair written and
// kept when they overlap. The pairs, packed into 64-bit keys, are sorted by radix.
void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<std::size_t, std::size_t>>& out,
                       SweepScratch& s) {
  out.clear();
  s.order.clear();
  for (std::size_t i = 0; i < boxes.size(); ++i)
    if (!boxes[i].empty()) s.order.push_back(i);
  std::sort(s.order.begin(), s.order.end(), [&](std::size_t a, std::size_t b) {
    return boxes[a].lo.x() < boxes[b].lo.x() || (boxes[a].lo.x() == boxes[b].lo.x() && a < b);
  });
  const std::size_t n = s.order.size();
  for (std::vector<double>* v : {&s.lo_x, &s.hi_x, &s.lo_y, &s.hi_y, &s.lo_z, &s.hi_z}) v->resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Aabb& b = boxes[s.order[k]];
    s.lo_x[k] = b.lo.x(), s.hi_x[k] = b.hi.x();
    s.lo_y[k] = b.lo.y(), s.hi_y[k] = b.hi.y();
    s.lo_z[k] = b.lo.z(), s.hi_z[k] = b.hi.z();
  }
  // A pair's key: the lower index above the higher, in as many bits as an index needs.
  if (boxes.size() > (std::size_t(1) << 31))
    throw std::length_error("peelcd::overlapping_pairs: more than 2^31 boxes");
  const int w = std::max(1, detail::bit_width(boxes.size()));
  s.keys.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const double hx = s.hi_x[i], ly = s.lo_y[i], hy = s.hi_y[i], lz = s.lo_z[i], hz = s.hi_z[i];
    std::size_t end = i + 1;
    while (end < n && s.lo_x[end] <= hx) ++end;
    if (end == i + 1) continue;
    const std::size_t at = s.keys.size();
    s.keys.resize(at + (end - i - 1));
    std::uint64_t* keys = s.keys.data() + at;
    std::size_t kept = 0;
    const std::uint64_t a = s.order[i];
    for (std::size_t j = i + 1; j < end; ++j) {
      const std::uint64_t b = s.order[j];
      keys[kept] = a < b ? (a << w | b) : (b << w | a);
      kept += (s.lo_y[j] <= hy) & (ly <= s.hi_y[j]) & (s.lo_z[j] <= hz) & (lz <= s.hi_z[j]);
    }
    s.keys.resize(at + kept);
  }
  if (s.keys.size() < detail::kRadixFrom)
    std::sort(s.keys.begin(), s.keys.end());
  else
    detail::radix_sort_bits(s.keys, s.spare, 0, 2 * w);
  out.resize(s.keys.size());
  const std::uint64_t low = (std::uint64_t(1) << w) - 1;
  for (std::size_t k = 0; k < s.keys.size(); ++k) out[k] = {std::size_t(s.keys[k] >> w), std::size_t(s.keys[k] & low)};
}

}  // namespace peelcd
