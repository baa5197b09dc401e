#include "peelcd/core/exact/self.h"

#include "apart_block.h"
#include "bvh_traverse.h"

#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/pairs.h"

#include <algorithm>
#include <numeric>

namespace peelcd {


void vertex_representatives(const Mesh& mesh, SelfAdjacency adjacency, std::vector<std::uint32_t>& out) {
  const std::size_t n = mesh.vertices.size();
  out.resize(n);
  std::iota(out.begin(), out.end(), 0u);
  if (adjacency == SelfAdjacency::index || n < 2) return;
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  const auto less = [&](std::uint32_t i, std::uint32_t j) {
    const Vec3& p = mesh.vertices[i];
    const Vec3& q = mesh.vertices[j];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return i < j;
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < n; ++k)
    if (mesh.vertices[order[k]] == mesh.vertices[order[k - 1]]) out[order[k]] = out[order[k - 1]];
}

const std::uint32_t* representatives_or_null(const std::vector<std::uint32_t>& rep) {
  for (std::size_t v = 0; v < rep.size(); ++v)
    if (rep[v] != v) return rep.data();
  return nullptr;
}

bool SelfTree::update(const Mesh& mesh) {
  return update(mesh, 1, [](std::size_t n, const auto& fn) {
    for (std::size_t k = 0; k < n; ++k) fn(k);
  });
}

std::size_t self_overlap_pairs(const Mesh& mesh, SelfTree& st, const std::vector<std::uint32_t>& rep,
                               std::vector<std::uint64_t>& out) {
  return self_overlap_visit(mesh, st, rep, [&](std::uint32_t t, std::uint32_t u) { out.push_back(pack_pair(t, u)); });
}

void self_candidates(const Mesh& mesh, const std::vector<std::uint32_t>& rep, std::vector<std::uint64_t>& pairs) {
  std::size_t w = 0;
  const std::uint32_t* r = representatives_or_null(rep);
  for (const std::uint64_t p : pairs) {
    std::uint32_t t = pair_a(p), u = pair_b(p);
    if (t == u || triangles_adjacent(mesh, r, t, u)) continue;
    if (u < t) std::swap(t, u);
    pairs[w++] = pack_pair(t, u);
  }
  pairs.resize(w);
  std::vector<std::uint64_t> scratch;
  sort_unique_pairs(pairs, scratch);
}

bool test_self_couple(const TriangleCorners& a, const TriangleCorners& b, Contact& contact) {
  return test_triangle_pair(a, b, contact);
}

void self_narrow_phase(const Mesh& mesh, const std::vector<std::uint64_t>& candidates, std::vector<Contact>& out,
                       std::size_t max_contacts, ContactDetail detail) {
  const std::size_t limit = max_contacts ? out.size() + max_contacts : std::size_t(-1);
  ContactTest test{detail};
  exact_detail::ApartBlock block;  // as narrow_phase(): the planes' test a block at a time first
  const exact_detail::TestInto test_left{test, out, limit};
  for (const std::uint64_t c : candidates) {
    block.put(pair_a(c), pair_b(c), corners(mesh, pair_a(c)), corners(mesh, pair_b(c)));
    if (block.full() && !block.drain(test_left)) return;
  }
  block.drain(test_left);
}

}  // namespace peelcd
