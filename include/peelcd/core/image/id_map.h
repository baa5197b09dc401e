#pragma once
// Triangle IDs written into the peel layers, and the triangle sets they stand for.
//   unique: ID = triangle index; it stands for that triangle only.
//   paper:  flat shading with the last vertex provoking; ID = index of the triangle's last
//           vertex v, standing for T(v) = every triangle whose last vertex is v.
//   ring:   the same ID (last vertex v), standing for the whole one-ring of v: every triangle
//           that has v as any of its corners (a larger neighbourhood, more candidates).
#include "peelcd/core/mesh.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/pairs.h"

#include <optional>
#include <string>
#include <vector>

namespace peelcd {


// ID that corner `corner` (0..2) of triangle `tri` carries as its flat vertex attribute. With the
// last-vertex provoking convention the fragment's ID is the value of corner 2.
inline std::uint32_t corner_id(const Mesh& mesh, std::uint32_t tri, int corner, IdMode mode) {
  return mode == IdMode::unique ? tri : mesh.triangles[tri][corner];
}

// CSR map from ID to the triangles it stands for.
class IdMap {
 public:
  IdMap() = default;
  IdMap(const Mesh& mesh, IdMode mode);
  // Rebuilds the map for `mesh` in place, reusing storage (no allocation once it has grown).
  // The map depends on the triangles and the vertex count only: when both (and the mode) are
  // those of the last build, as for a rigid or deforming mesh from frame to frame, it is kept.
  void rebuild(const Mesh& mesh, IdMode mode);

  IdMode mode() const { return mode_; }
  std::size_t id_count() const { return offsets_.empty() ? 0 : offsets_.size() - 1; }
  const std::uint32_t* begin(std::uint32_t id) const { return tris_.data() + offsets_[id]; }
  const std::uint32_t* end(std::uint32_t id) const { return tris_.data() + offsets_[id + 1]; }
  std::vector<std::uint32_t> triangles(std::uint32_t id) const { return {begin(id), end(id)}; }

 private:
  IdMode mode_ = IdMode::unique;
  std::vector<std::uint32_t> offsets_;  // id_count() + 1
  std::vector<std::uint32_t> tris_;
  std::vector<std::uint32_t> fill_, scratch_;
  std::vector<Tri> built_from_;  // the triangles of the last build
  std::size_t built_vertices_ = 0;
  bool built_ = false;
};


// Expands ID pairs into candidate triangle pairs T(a) x T(b), appended to `out`, then sorts and
// de-duplicates `out`. IDs out of range are an error (std::out_of_range). `scratch` is reused
// storage (no allocation once grown); the overload without it allocates its own.
void expand_pcs(const std::vector<IdPair>& pcs, const IdMap& a, const IdMap& b, std::vector<std::uint64_t>& out,
                std::vector<std::uint64_t>& scratch);
void expand_pcs(const std::vector<IdPair>& pcs, const IdMap& a, const IdMap& b,
                std::vector<std::uint64_t>& out);


}  // namespace peelcd
