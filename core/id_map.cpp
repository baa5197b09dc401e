#include "core/id_map.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {

const char* to_string(IdMode mode) { return mode == IdMode::unique ? "unique" : "paper"; }

std::optional<IdMode> parse_id_mode(const std::string& text) {
  if (text == "unique") return IdMode::unique;
  if (text == "paper") return IdMode::paper;
  return std::nullopt;
}

IdMap::IdMap(const Mesh& mesh, IdMode mode) : mode_(mode) {
  const std::size_t f = mesh.triangles.size();
  const std::size_t ids = mode == IdMode::unique ? f : mesh.vertices.size();
  offsets_.assign(ids + 1, 0);
  for (std::uint32_t t = 0; t < f; ++t) ++offsets_[corner_id(mesh, t, 2, mode) + 1];
  for (std::size_t i = 0; i < ids; ++i) offsets_[i + 1] += offsets_[i];
  tris_.resize(f);
  std::vector<std::uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
  for (std::uint32_t t = 0; t < f; ++t) tris_[fill[corner_id(mesh, t, 2, mode)]++] = t;
}

void expand_pcs(const std::vector<IdPair>& pcs, const IdMap& a, const IdMap& b,
                std::vector<std::uint64_t>& out) {
  for (const IdPair& p : pcs) {
    if (p.a >= a.id_count() || p.b >= b.id_count())
      throw std::out_of_range("peelcd::expand_pcs(): triangle ID out of range");
    for (const std::uint32_t* ta = a.begin(p.a); ta != a.end(p.a); ++ta)
      for (const std::uint32_t* tb = b.begin(p.b); tb != b.end(p.b); ++tb)
        out.push_back(pack_pair(*ta, *tb));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace peelcd
