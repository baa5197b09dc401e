#pragma once
// How two objects of a frame relate, beyond their touching triangles (docs/design.md,
// "Containment and intersection volume"): disjoint, touching, crossing, or one wholly inside the
// other with no surface contact, which is a collision too. Containment needs a closed container
// (every edge shared by exactly two triangles); where it would be needed and the container is
// open or non-manifold, the relation is "unknown", with the reason.
//
// The intersection volume (opt in: DetectOptions::volume) of two closed, outward-oriented
// meshes is estimated in image space: rays through the centres of an N x N grid of texels over
// the overlap box, along each world axis, meet both meshes' triangles (exact coverage: a texel
// centre on a shared edge or vertex belongs to exactly one of the triangles around it); along
// each ray the winding of each mesh gives where it is inside, and the lengths where both are
// inside, times the texel's area, sum to the volume. Its derivative with respect to a
// translation of A, the integral of A's outward normal over A's surface inside B, comes from the
// same crossings (Faure et al. 2008): moving A along -gradient reduces the overlap fastest.
#include "peelcd/core/aabb.h"
#include "peelcd/core/mesh.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/pair_outcomes.h"

#include <optional>
#include <string>
#include <vector>

namespace peelcd {


// What a mesh is, for containment and volume.
struct MeshShape {
  bool closed = false;            // every edge shared by exactly two triangles
  bool oriented = false;          // closed, and each edge traversed once in each direction
  std::size_t boundary_edges = 0, nonmanifold_edges = 0, misoriented_edges = 0;
  double signed_volume = 0.0;     // > 0: outward (counter-clockwise seen from outside)
  std::vector<std::uint32_t> component_vertex;  // one vertex of each connected component
  // Empty when the mesh is closed, oriented and outward; else why it is not, in words
  // ("open: 12 boundary edges", "inside out: its signed volume is negative", ...).
  std::string problem() const;
};
MeshShape analyse_shape(const Mesh& mesh);

// `p` lies strictly inside the closed mesh `container` (exact predicates: CGAL's
// Side_of_triangle_mesh). `p` must not lie on its surface.
bool point_inside(const Mesh& container, const Vec3& p);

// The relation of A and B given their contacts (a frame's pair): crossing when some contact
// penetrates, touching when all merely touch; with none, containment tested where A's box
// lies within B's (or B's within A's) and the container is closed: one vertex of each connected
// component of the inner mesh, exactly; unknown (with `note`) when the container is open.
Relation relate(const Mesh& a, const Mesh& b, const std::vector<Contact>& contacts, std::string& note);
// The relation the contacts alone give: crossing when one penetrates, touching when all merely
// touch, disjoint when there is none (a self pair's relation; the first step of relate()).
Relation contact_relation(const std::vector<Contact>& contacts);
// Touching contacts only (no crossing) may still hide a shared interior: a closed mesh inside
// another that touches its surface from inside (a box in a box sharing a face). Where one box
// lies within the other and the outer mesh is closed, the centroid of a triangle of the inner
// mesh in no contact (so off the outer surface) is tested exactly: inside, the relation is
// containment (note: "touches ... from inside"). Two closed meshes of one surface (a mesh and
// its copy at the same pose: every triangle of one is a triangle of the other) share their whole
// interior: `a_inside_b` (note: "A and B coincide ..."). Otherwise `touching` stays. The contacts must be complete (not cut by max_contacts).
Relation touching_relation(const Mesh& a, const Mesh& b, const Aabb& box_a, const Aabb& box_b,
                           const std::vector<Contact>& contacts, std::string& note);
// The same with the meshes' boxes known (nothing read when no box lies within the other).
Relation relate(const Mesh& a, const Mesh& b, const Aabb& box_a, const Aabb& box_b, const std::vector<Contact>& contacts,
                std::string& note);


// The intersection volume of two closed meshes over `roi` (their boxes' overlap), N x N rays per
// axis. Open or inside-out meshes give known = false and the reason.
VolumeEstimate overlap_volume(const Mesh& a, const Mesh& b, const Aabb& roi, int resolution);

// Per texel of an n x n image seen along `d` over the square [-half_uv, half_uv]^2 of the (u, v)
// plane through `center` (texel (i, j) at j * n + i, u to the right, v up: a ROI view's layout),
// the length along d, within [-half_depth, half_depth], where both closed meshes are inside:
// the "inside intervals" a dump shows. Empty when a mesh is not closed and outward: returns
// why, in words ("A is open: ..."); else empty.
std::string overlap_lengths(const Mesh& a, const Mesh& b, const Vec3& center, const Vec3& u, const Vec3& v, const Vec3& d,
                            double half_uv, double half_depth, int n, std::vector<float>& out);

// The exact volume of the intersection (CGAL's corefinement with exact constructions, then
// volume()): the check of overlap_volume(). Throws std::runtime_error when CGAL refuses the
// meshes (open, self-intersecting).
double exact_overlap_volume(const Mesh& a, const Mesh& b);

// Fills each pair's relation (and with options.volume its volume) from its contacts and the
// objects' meshes: `mesh_of(i)` gives object i's world mesh (called only when needed). With
// options.margin, also each pair's `near` by a tree search, except for the pairs whose
// `near_found[i]` is set (their stage found them from its candidates).
// `lanes`, given: its for_pairs(n, fn) runs fn(i) for i in [0, n), in any order and on any
// threads; the pairs whose answers come from their contacts alone are related through it, those
// that read a mesh (mesh_of) or a tree after, on the calling thread, in pair order (`left`:
// scratch, kept by a caller that relates every frame).
struct RelateLanes {
  std::function<void(std::size_t, const std::function<void(std::size_t)>&)> for_pairs;
  std::vector<char> left;
};
void relate_pairs(std::vector<PairResult>& pairs, const std::function<const Mesh&(std::size_t)>& mesh_of,
                  const std::vector<Aabb>& boxes, const DetectOptions& options,
                  const std::vector<char>* near_found = nullptr, RelateLanes* lanes = nullptr);

}  // namespace peelcd
