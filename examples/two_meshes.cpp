// Two meshes built from arrays, one collision query, no GL at all (the CPU image stage).
#include "core/mesh.h"  // this project's own header

#include <peelcd/peelcd.h>

#include <cstdio>

int main() {
  const app::Mesh mine{1};
  // A tetrahedron and a triangle that pierces it.
  peelcd::Mesh tetra;
  tetra.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  peelcd::Mesh blade;
  blade.vertices = {{-0.5, 0.2, 0.2}, {1.5, 0.2, 0.2}, {0.2, 0.2, 1.5}};
  blade.triangles = {{0, 1, 2}};

  peelcd::Detector detector(std::make_shared<peelcd::CpuImageStage>());
  peelcd::CollisionRequest request;
  peelcd::CollisionResult result;
  const std::size_t n = peelcd::collide(detector, tetra, Eigen::Affine3d::Identity(), blade,
                                        Eigen::Affine3d::Identity(), request, result);
  std::printf("peelcd %s: %zu colliding triangle pairs (app mesh %d)\n", peelcd::version_string(), n, mine.id);
  for (const peelcd::Contact& c : result.contacts)
    std::printf("  tetra %u x blade %u: %s, segment (%.3f %.3f %.3f) - (%.3f %.3f %.3f)\n", c.tri_a, c.tri_b,
                peelcd::to_string(c.kind), c.p.x(), c.p.y(), c.p.z(), c.q.x(), c.q.y(), c.q.z());
  return n > 0 ? 0 : 1;  // the blade crosses three faces of the tetrahedron
}
