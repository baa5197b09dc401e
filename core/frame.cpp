#include "core/frame.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {

const char* to_string(PeelMode mode) { return mode == PeelMode::full ? "full" : "alternate"; }

std::optional<PeelMode> parse_peel_mode(const std::string& text) {
  if (text == "full") return PeelMode::full;
  if (text == "alternate" || text == "paper") return PeelMode::alternate;
  return std::nullopt;
}

int tile_resolution(int budget, std::size_t roi_count) {
  if (budget <= 0) throw std::invalid_argument("peelcd::tile_resolution(): budget must be positive");
  int n = budget;
  std::size_t per_side = 1;
  while (per_side * per_side < roi_count && n > 16) {
    per_side *= 2;
    n /= 2;
  }
  return std::max(n, std::min(budget, 16));
}

}  // namespace peelcd
