#include "peelcd/core/id_map.h"

#include "radix_sort.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {

const char* to_string(IdMode mode) {
  switch (mode) {
    case IdMode::unique: return "unique";
    case IdMode::paper: return "paper";
    case IdMode::ring: return "ring";
  }
  return "?";
}

std::optional<IdMode> parse_id_mode(const std::string& text) {
  if (text == "unique") return IdMode::unique;
  if (text == "paper") return IdMode::paper;
  if (text == "ring") return IdMode::ring;
  return std::nullopt;
}

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

void sort_unique_pairs(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& scratch) {
  if (keys.size() < 512) {  // a radix pass costs a histogram: not worth it
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return;
  }
  std::uint32_t max_a = 0, max_b = 0;
  for (const std::uint64_t k : keys) max_a = std::max(max_a, pair_a(k)), max_b = std::max(max_b, pair_b(k));
  // Compact keys: a << bits_b | b keeps the order of (a, b) in bits_a + bits_b bits.
  const int bits_b = detail::bit_width(max_b), bits = detail::bit_width(max_a) + bits_b;
  for (std::uint64_t& k : keys) k = (std::uint64_t(pair_a(k)) << bits_b) | pair_b(k);
  detail::radix_sort_bits(keys, scratch, 0, bits);
  // Back to pack_pair keys, dropping repeats (now adjacent).
  const std::uint64_t mask_b = bits_b == 0 ? 0 : (~std::uint64_t(0) >> (64 - bits_b));
  std::size_t n = 0;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (i == 0 || keys[i] != keys[i - 1]) keys[n++] = keys[i];
  keys.resize(n);
  for (std::uint64_t& k : keys) k = pack_pair(std::uint32_t(k >> bits_b), std::uint32_t(k & mask_b));
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
