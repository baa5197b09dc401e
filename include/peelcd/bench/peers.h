#pragma once
// What a user would pick instead of peelcd, run on the same frames (peelcd bench):
//   cgal: per object pair with overlapping boxes, CGAL box_intersection_d over the triangles'
//         boxes plus the exact triangle test (core/reference.h): the fastest exact method that
//         needs no preprocessing, and the reference nCTP.
//   fcl:  FCL 0.7, a BVH (AABB tree) built for every object in an overlapping pair, every frame
//         (what a deforming or fracturing mesh costs there), then collided with all contacts
//         (collide()'s traversal, without its model copies: see peers.cpp).
// Both use the same object-level broad phase as peelcd (core/broad_phase.h).
#include "peelcd/core/mesh.h"

#include <cstdint>
#include <vector>

namespace peelcd::bench {

struct PeerFrame {
  double ms = 0;
  std::size_t pairs = 0;  // colliding triangle pairs reported (all object pairs summed)
  std::vector<std::pair<std::size_t, std::size_t>> objects;  // the overlapping object pairs
  // Per overlapping object pair (a, b) in broad-phase order: the reported triangle pairs,
  // packed as core/id_map.h pair keys (tri_a << 32 | tri_b), sorted.
  std::vector<std::vector<std::uint64_t>> per_pair;
};

PeerFrame cgal_frame(const std::vector<Object>& objects);
PeerFrame fcl_frame(const std::vector<Object>& objects);

}  // namespace peelcd::bench
