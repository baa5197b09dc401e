#include "peelcd/core/broad_phase.h"

#include <algorithm>
#include <numeric>

namespace peelcd {

std::vector<std::pair<std::size_t, std::size_t>> overlapping_pairs(const std::vector<Aabb>& boxes) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::vector<std::size_t> order;
  overlapping_pairs(boxes, out, order);
  return out;
}

void overlapping_pairs(const std::vector<Aabb>& boxes, std::vector<std::pair<std::size_t, std::size_t>>& out,
                       std::vector<std::size_t>& order) {
  order.resize(boxes.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return boxes[a].lo.x() < boxes[b].lo.x() || (boxes[a].lo.x() == boxes[b].lo.x() && a < b);
  });
  out.clear();
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Aabb& a = boxes[order[i]];
    if (a.empty()) continue;
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Aabb& b = boxes[order[j]];
      if (b.lo.x() > a.hi.x()) break;
      if (!b.empty() && a.overlaps(b))
        out.emplace_back(std::min(order[i], order[j]), std::max(order[i], order[j]));
    }
  }
  std::sort(out.begin(), out.end());
}

}  // namespace peelcd
