// A frame's per-pair answers beyond the contacts (relate_pairs(), peelcd/core/exact/relation.h):
// relation, volume, penetration depth and proximity, from the contacts and the meshes.
#include "peelcd/core/exact/relation.h"

#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/exact/depth.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/exact/self.h"

#include <map>

namespace peelcd {

void relate_pairs(std::vector<PairResult>& pairs, const std::function<const Mesh&(std::size_t)>& mesh_of,
                  const std::vector<Aabb>& boxes, const DetectOptions& options, const std::vector<char>* near_found,
                  RelateLanes* lanes) {
  const int n = options.resolution > 0 ? options.resolution : kVolumeResolution;
  // The margin's trees, one per object, built on its first pair (none without a margin).
  std::map<std::size_t, Bvh> trees;
  const auto tree_of = [&](std::size_t id) -> const Bvh& {
    auto it = trees.find(id);
    if (it == trees.end()) {
      it = trees.emplace(id, Bvh{}).first;
      it->second.build(mesh_of(id).vertices, mesh_of(id).triangles);
    }
    return it->second;
  };
  // Pair pi related; with `meshes` false, returns false where it needs a mesh or a tree (the
  // steps before are done again by the call with `meshes` true: they give the same values).
  const bool reads_meshes = options.margin > 0.0 || options.depth || options.volume;
  const auto relate_one = [&](std::size_t pi, bool meshes) {
    if (!meshes && reads_meshes) return false;
    PairResult& p = pairs[pi];
    const bool found = near_found && (*near_found)[pi];
    p.relation_note.clear();
    p.volume = VolumeEstimate{};
    p.depth = PenetrationDepth{};
    if (!found) p.near = Proximity{};
    // max_contacts: a pair's lanes may each have stopped at N; the first N, sorted, are kept.
    const bool capped = options.max_contacts && p.colliding.size() >= options.max_contacts;
    if (capped) p.colliding.resize(options.max_contacts);
    const auto note_cap = [&] {
      if (capped)
        p.relation_note = "max_contacts " + std::to_string(options.max_contacts) +
                          ": the relation is from the contacts found before the tests stopped";
    };
    if (p.object_a == p.object_b) {  // self: from the contacts alone
      p.relation = contact_relation(p.colliding);
      note_cap();
      if (options.margin > 0.0) {
        std::vector<std::uint32_t> rep;
        vertex_representatives(mesh_of(p.object_a), options.self_adjacency, rep);
        p.near = near_self_pairs(mesh_of(p.object_a), tree_of(p.object_a), rep, options.margin);
      }
      return true;
    }
    if (options.margin > 0.0 && !found)
      p.near = near_pairs(mesh_of(p.object_a), mesh_of(p.object_b), tree_of(p.object_b), options.margin);
    const Aabb& ba = boxes[p.object_a];
    const Aabb& bb = boxes[p.object_b];
    const bool within = !ba.empty() && !bb.empty() &&
                        (((ba.lo.array() >= bb.lo.array()).all() && (ba.hi.array() <= bb.hi.array()).all()) ||
                         ((bb.lo.array() >= ba.lo.array()).all() && (bb.hi.array() <= ba.hi.array()).all()));
    if (!p.colliding.empty() || !within) {  // from the contacts: no mesh read
      p.relation = contact_relation(p.colliding);
      note_cap();
      // Touching only, one box within the other: touching from inside is containment.
      if (p.relation == Relation::touching && within && !capped) {
        if (!meshes) return false;
        p.relation = touching_relation(mesh_of(p.object_a), mesh_of(p.object_b), ba, bb, p.colliding, p.relation_note);
      }
    } else {
      if (!meshes) return false;
      p.relation = relate(mesh_of(p.object_a), mesh_of(p.object_b), ba, bb, p.colliding, p.relation_note);
    }
    if (options.depth) {
      if (colliding_relation(p.relation))
        p.depth = penetration_depth(mesh_of(p.object_a), mesh_of(p.object_b), p.colliding);
      else
        p.depth.reason = p.relation == Relation::unknown ? "the relation is unknown: " + p.relation_note
                                                         : std::string("the objects do not collide");
    }
    if (options.volume) {
      if (p.relation == Relation::disjoint) {  // no overlap: nothing to integrate, 0 if both are closed
        p.volume = overlap_volume(mesh_of(p.object_a), mesh_of(p.object_b), Aabb{}, n);
      } else {
        p.volume = overlap_volume(mesh_of(p.object_a), mesh_of(p.object_b), p.roi, n);
      }
    }
    return true;
  };
  if (!lanes || reads_meshes || pairs.size() < 2) {
    for (std::size_t pi = 0; pi < pairs.size(); ++pi) relate_one(pi, true);
    return;
  }
  std::vector<char>& left = lanes->left;
  left.assign(pairs.size(), 0);
  lanes->for_pairs(pairs.size(), [&](std::size_t pi) { left[pi] = !relate_one(pi, false); });
  for (std::size_t pi = 0; pi < pairs.size(); ++pi)
    if (left[pi]) relate_one(pi, true);
}

}  // namespace peelcd
