#pragma once
// The intersection-volume benchmark of `peelcd bench volume`: two closed spheres of about
// 100k triangles each, overlapping deeply; peelcd's image-space volume (overlap_volume(), at the
// default 256 rays per axis and at 512) against CGAL's exact corefinement and volume(); medians
// over the frames (the spheres turn a little each frame), relative errors against CGAL's.
#include <string>
#include <utility>
#include <vector>

#include "peelcd/core/mesh.h"

namespace peelcd::bench {

struct VolumeSuite {
  int stacks = 158;  // UV spheres of 4 s (s - 1) triangles (158: 99,224)
  std::size_t frames = 3;
  // The error estimate's coverage: closed meshes (loaded by the caller), each pair of consecutive
  // ones in random relative poses, `coverage_frames` each; empty: no coverage table.
  std::vector<std::pair<std::string, Mesh>> coverage_meshes;
  std::size_t coverage_frames = 0;
};

// Prints the table on stdout; returns the CSV (method,frame,ms,volume,exact).
std::string run_volume_suite(const VolumeSuite& suite);

}  // namespace peelcd::bench
