#include "peelcd/core/image/id_map.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {


IdMap::IdMap(const Mesh& mesh, IdMode mode) { rebuild(mesh, mode); }

void IdMap::rebuild(const Mesh& mesh, IdMode mode) {
  if (built_ && mode == mode_ && mesh.vertices.size() == built_vertices_ && mesh.triangles == built_from_) return;
  mode_ = mode;
  const std::size_t f = mesh.triangles.size();
  const std::size_t ids = mode == IdMode::unique ? f : mesh.vertices.size();
  // Corners of triangle t that name an ID standing for t: the last one, or all three (ring).
  const int first_corner = mode == IdMode::ring ? 0 : 2;
  offsets_.assign(ids + 1, 0);
  for (std::uint32_t t = 0; t < f; ++t)
    for (int c = first_corner; c < 3; ++c) ++offsets_[corner_id(mesh, t, c, mode) + 1];
  for (std::size_t i = 0; i < ids; ++i) offsets_[i + 1] += offsets_[i];
  tris_.resize(offsets_.back());
  fill_.assign(offsets_.begin(), offsets_.end() - 1);
  for (std::uint32_t t = 0; t < f; ++t)
    for (int c = first_corner; c < 3; ++c) {
      const std::uint32_t id = corner_id(mesh, t, c, mode);
      // A degenerate triangle can repeat a vertex: list it once.
      if (fill_[id] > offsets_[id] && tris_[fill_[id] - 1] == t) continue;
      tris_[fill_[id]++] = t;
    }
  // Compact away the slots left by repeated vertices.
  std::size_t out = 0;
  scratch_.assign(ids + 1, 0);
  for (std::size_t id = 0; id < ids; ++id) {
    scratch_[id] = std::uint32_t(out);
    for (std::uint32_t k = offsets_[id]; k < fill_[id]; ++k) tris_[out++] = tris_[k];
  }
  scratch_[ids] = std::uint32_t(out);
  tris_.resize(out);
  offsets_.swap(scratch_);
  built_from_.assign(mesh.triangles.begin(), mesh.triangles.end());
  built_vertices_ = mesh.vertices.size();
  built_ = true;
}


void expand_pcs(const std::vector<IdPair>& pcs, const IdMap& a, const IdMap& b,
                std::vector<std::uint64_t>& out) {
  std::vector<std::uint64_t> scratch;
  expand_pcs(pcs, a, b, out, scratch);
}

void expand_pcs(const std::vector<IdPair>& pcs, const IdMap& a, const IdMap& b, std::vector<std::uint64_t>& out,
                std::vector<std::uint64_t>& scratch) {
  for (const IdPair& p : pcs) {
    if (p.a >= a.id_count() || p.b >= b.id_count())
      throw std::out_of_range("peelcd::expand_pcs(): triangle ID out of range");
    for (const std::uint32_t* ta = a.begin(p.a); ta != a.end(p.a); ++ta)
      for (const std::uint32_t* tb = b.begin(p.b); tb != b.end(p.b); ++tb)
        out.push_back(pack_pair(*ta, *tb));
  }
  sort_unique_pairs(out, scratch);
}

}  // namespace peelcd
