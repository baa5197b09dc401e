#pragma once
// The query benchmarks of `peelcd bench depth` and `peelcd bench distance`:
// - depth: penetration_depth() (peelcd/core/exact/depth.h) per scene, timed, against a reference along
//   the same direction: bisection on translations of A along n (60 halvings between 0 and a
//   translation that clears B's extent), each step decided by the exact path (crossing or
//   containment: overlapping); the relative difference of the two depths;
// - distance: the least distance of two disjoint objects, peelcd's proximity pass
//   (near_pairs(), a margin of twice FCL's distance) against FCL 0.7's distance query
//   (fcl::distance between two OBBRSS trees built once, as a user keeps them).
// Medians over the frames (the same query repeated).
#include "peelcd/core/mesh.h"

#include <string>
#include <vector>

namespace peelcd::bench {

struct QueryScene {
  std::string name;
  Mesh a, b;
};

struct QuerySuite {
  std::vector<QueryScene> scenes;
  std::size_t frames = 5;
};

// Prints the table on stdout; returns the CSV (scene,method,frame,ms,value).
std::string run_depth_suite(const QuerySuite& suite);
std::string run_distance_suite(const QuerySuite& suite);

}  // namespace peelcd::bench
