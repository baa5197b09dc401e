#pragma once
// The self-collision benchmarks of `peelcd bench cloth-self` (a folded cloth folding through
// itself) and `peelcd bench cloth-crumpled` (a cloth crumpled over a ball, its folds drifting):
// one deforming object, self-collision on; peelcd's World (its kept tree refitted, traversed
// against itself), the frame API (stage router, exact path's sweep, image stage forced) against
// Embree's rtcCollide of the cloth's scene with itself and Bullet's GImpact box set against
// itself (both refitted, Moller's float test: peelcd/bench/float_peers.h), a BVH self-test with
// its tree kept and refitted (no World around it) and CGAL's
// Polygon_mesh_processing::self_intersections; medians per frame after an untimed pass, misses
// and false pairs against the exact self pairs.
#include "peelcd/core/image/image_stage.h"

#include <memory>
#include <string>

namespace peelcd::bench {

struct SelfSuite {
  // false: the folding sheet (make_folded_sheet(n): 6 n^2 triangles, 130: 101,400); true: the
  // crumpled cloth (make_crumpled_cloth(n): 2 n^2 triangles, 224: 100,352).
  bool crumpled = false;
  int n = 130;
  std::size_t frames = 8;
  std::shared_ptr<ImageStage> stage;  // the frame API's image stage
  // A row of Embree's scene against itself as a plain user sets it up (PlainPeer), and each
  // Embree self row's ratio to it under the table (docs/performance.md, "The audit").
  bool audit = false;
  // > 0: after the table, the World's default and the frame API's exact path with this many
  // threads against one thread, each pair of rows alone, alternating frame by frame.
  unsigned scaling = 0;
};

// Prints the table on stdout; returns the CSV (method,frame,ms,exact,found,missed).
std::string run_self_suite(const SelfSuite& suite);

}  // namespace peelcd::bench
