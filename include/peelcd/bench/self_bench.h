#pragma once
// The self-collision benchmark of `peelcd bench --scene cloth-self`: a folded cloth (one
// deforming object, self-collision on) folding through itself over the frames; peelcd's
// World (its kept tree refitted, traversed against itself), the frame API (stage router, exact
// path's sweep, image stage forced) against a BVH self-test with its tree kept and refitted
// (no World around it) and CGAL's Polygon_mesh_processing::self_intersections; medians per
// frame after an untimed pass, misses against the exact self pairs.
#include "peelcd/core/image_stage.h"

#include <memory>
#include <string>

namespace peelcd::bench {

struct SelfSuite {
  int n = 130;              // make_folded_sheet(n): 6 n^2 triangles (130: 101,400)
  std::size_t frames = 8;
  std::shared_ptr<ImageStage> stage;  // the frame API's image stage
};

// Prints the table on stdout; returns the CSV (method,frame,ms,exact,found,missed).
std::string run_self_suite(const SelfSuite& suite);

}  // namespace peelcd::bench
