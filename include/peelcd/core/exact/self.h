#pragma once
// Self-collision of one object (docs/design.md, "Self-collision"): two triangles of one mesh
// collide when they share a point and share no vertex. Triangles that share a vertex (adjacent
// triangles, and a fan around a vertex) touch by construction and are never reported, even
// where they also meet elsewhere (a fold sharp enough for two triangles of one fan to cross).
// Which vertices count as shared is the adjacency: by index (the mesh's connectivity, the
// default), or by position (vertices at bitwise-equal coordinates are one vertex: the seams of
// an OBJ whose patches duplicate their border vertices, or a soup of unwelded triangles).
// A self pair is listed like an inter-object pair with object A = object B, tri_a < tri_b.
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/exact/narrow_phase.h"

#include <optional>
#include <string>
#include <vector>

namespace peelcd {


// Per vertex, the vertex that stands for it: itself (index), or the first vertex at the same
// coordinates (position). Two triangles are adjacent when they share a representative.
void vertex_representatives(const Mesh& mesh, SelfAdjacency adjacency, std::vector<std::uint32_t>& out);

// Triangles t and u share a vertex: their vertices' representatives compared (`rep`,
// vertex_representatives()), or, rep null, their vertex indices (SelfAdjacency::index, whose
// representatives are the indices: six loads fewer a couple). A triangle is adjacent to itself.
// Inline and without branches: a self traversal asks it of every couple of overlapping boxes
// (15% of the folded sheet's frame when it was a call with early exits).
inline bool triangles_adjacent(const Mesh& mesh, const std::uint32_t* rep, std::uint32_t t, std::uint32_t u) {
  const Tri& a = mesh.triangles[t];
  const Tri& b = mesh.triangles[u];
  std::uint32_t x[3], y[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = rep ? rep[a[i]] : a[i];
    y[i] = rep ? rep[b[i]] : b[i];
  }
  unsigned same = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) same |= unsigned(x[i] == y[j]);
  return same != 0;
}
inline bool triangles_adjacent(const Mesh& mesh, const std::vector<std::uint32_t>& rep, std::uint32_t t, std::uint32_t u) {
  return triangles_adjacent(mesh, rep.data(), t, u);
}
// `rep` itself where it maps some vertex elsewhere, null where it is the identity (every vertex
// its own representative): the argument triangles_adjacent() compares fastest with.
const std::uint32_t* representatives_or_null(const std::vector<std::uint32_t>& rep);

// A mesh's tree for its self search, kept from frame to frame (the frame API keeps one per
// object that asks for self-collision): refitted while the triangles stay the same, built again
// when they change, and when refits have grown it past kBvhRebuildGrowth (Bvh::rebuild_if_grown:
// a refit keeps the grouping of the first frame; a cloth that crumples far from it overlaps more
// of itself).
struct SelfTree {
  Bvh tree;
  std::vector<Tri> triangles;  // of the last build
  std::size_t builds = 0;
  std::vector<BvhNodePair> stack;  // the traversal's scratch, kept with the tree
  // Brings the tree to `mesh`: built for new triangles, else refitted, and built again when
  // the refit grew it past kBvhRebuildGrowth (as the World's deforming bodies). Returns true
  // when it was built.
  bool update(const Mesh& mesh);
  // The same with a build in `parts` subtrees (Bvh::plan_build(): the same tree) run by
  // for_each(n, fn), which calls fn(k) for every k < n, possibly concurrently.
  template <class ForEach>
  bool update(const Mesh& mesh, std::size_t parts, ForEach&& for_each) {
    bool build = builds == 0 || tree.empty() != mesh.triangles.empty() || triangles != mesh.triangles;
    if (!build) {
      tree.refit(mesh.vertices, mesh.triangles);
      build = tree.grown();
    }
    if (build) {
      const std::size_t n = tree.plan_build(mesh.vertices, mesh.triangles, parts);
      for_each(n, [this](std::size_t k) { tree.build_part(k); });
      tree.finish_build(mesh.triangles);
      if (triangles != mesh.triangles) triangles = mesh.triangles;
    }
    builds += build;
    return build;
  }
};


// Every candidate self couple of `mesh` (two triangles whose closed boxes overlap and that are
// not adjacent) through the kept tree `st`, brought to `mesh` first and traversed against itself
// (no n^2), appended as pack_pair(t, u) with t < u (self_overlap_visit() in
// core/exact/bvh_traverse.h visits them instead). Returns the
// node pairs visited.
std::size_t self_overlap_pairs(const Mesh& mesh, SelfTree& st, const std::vector<std::uint32_t>& rep,
                               std::vector<std::uint64_t>& out);

// Makes image-stage candidates (pack_pair(ID of A, ID of B) of the same mesh peeled twice) self
// candidates: each pair as (min, max), adjacent pairs and a triangle with itself dropped, sorted
// and unique.
void self_candidates(const Mesh& mesh, const std::vector<std::uint32_t>& rep, std::vector<std::uint64_t>& pairs);

// The exact test of one self couple (two triangles of one object, not adjacent):
// test_triangle_pair(). A smooth surface's neighbours, nearly coplanar, whose signs are near 0
// where the certified double signs give up, are mostly separated there by an edge's plane
// (apart_across_an_edge()) before any exact arithmetic; sending nearly parallel couples to
// CGAL's filtered test first instead made the crumpled cloth's frame 1.08x slower (the folded
// sheet's the same).
bool test_self_couple(const TriangleCorners& a, const TriangleCorners& b, Contact& contact);

// Every self candidate (pack_pair(t, u)) through test_self_couple(), the colliding appended to
// `out` in candidate order.
// max_contacts > 0: stops once `out` has gained that many (DetectOptions::max_contacts).
// detail: what each contact holds (ContactTest; DetectOptions::contacts).
void self_narrow_phase(const Mesh& mesh, const std::vector<std::uint64_t>& candidates, std::vector<Contact>& out,
                       std::size_t max_contacts = 0, ContactDetail detail = ContactDetail::segments);

// The exact self reference: every non-adjacent couple of triangles that share a point, through
// CGAL's box_self_intersection_d and the exact triangle test; pack_pair(t, u), t < u, sorted
// (core/exact/reference.cpp, beside the two-object reference).
std::vector<std::uint64_t> exact_self_pairs(const Mesh& mesh, SelfAdjacency adjacency = SelfAdjacency::index);

}  // namespace peelcd
