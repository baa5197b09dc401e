#pragma once
// The paper's two dynamic test scenes as frame sequences (docs/design.md section 3, Tables 1 and 2).
// No physics: the motion is scripted so that contact rises over four phases, and every frame is
// a fresh set of world-space meshes (peelcd precomputes nothing, so a deforming or fracturing
// mesh costs the same as a rigid one).
//
//   test1: the velociraptor (standing in for the paper's lizard) walks across a table of 40
//          billiard balls (UV spheres, 4,512 triangles each), its body bent by a travelling
//          wave; it enters the ball field, walks through it, then crouches into it.
//   test2: a cloth of 1,568 triangles tears along a line that grows every frame (crossed
//          triangles split, the far side gets its own vertices and falls away) while 40 objects
//          (the fixtures' meshes, 1.2K-4.6K triangles) fall through it, some through each other.
#include "peelcd/core/mesh.h"

#include <memory>
#include <string>
#include <vector>

namespace peelcd {

class Sequence {
 public:
  virtual ~Sequence() = default;
  virtual std::string name() const = 0;
  std::size_t frames() const { return frames_; }
  // Phases as in the paper's tables: test1 has 4, (a)..(d); test2 has 8, (a)..(h).
  virtual int phases() const = 0;
  int phase(std::size_t f) const {
    return int(std::min<std::size_t>(phases() - 1, phases() * f / std::max<std::size_t>(frames_, 1)));
  }
  // Writes frame f into `objects` (resized to the scene's object count; storage reused).
  virtual void frame(std::size_t f, std::vector<Object>& objects) const = 0;

 protected:
  explicit Sequence(std::size_t frames) : frames_(frames) {}
  std::size_t frames_;
};

// `meshes_dir` holds the fixtures' meshes (fixtures/meshes). Throws InputError if one is missing.
// `rigid`: the rigid objects (balls, falling objects) carry their RigidMotion, so the GL
// pipeline uploads their shapes once; without it every object is plain world-space triangles.
std::unique_ptr<Sequence> make_test1(const std::string& meshes_dir, std::size_t frames, bool rigid = true);
std::unique_ptr<Sequence> make_test2(const std::string& meshes_dir, std::size_t frames, bool rigid = true);

// A crowd: `objects` balls (UV spheres of 24 x 12 quads, 528 triangles, radius 0.5) in a pile
// of two layers, the lower on a square grid 0.99 of a diameter apart, the upper resting in the
// lower's hollows 0.01 deep: every ball in light contact with its neighbours (about 2 contacts
// per ball below, 4 above). Each frame every ball turns a little and jiggles by up to 0.004
// (rigid motion), and every fifth ball breathes (its radius varies by 0.4%: a deforming mesh,
// new vertices every frame). One phase.
std::unique_ptr<Sequence> make_crowd(std::size_t objects, std::size_t frames, bool rigid = true);

// Two crossing spheres for scale: UV spheres of radius 1 with `stacks` latitude bands and
// 2 * stacks sectors (4 * stacks * (stacks - 1) triangles: 288 -> 330,624, 570 -> 1,297,320),
// centres 1.2 apart, so that they cross along a circle of radius 0.8. Each frame both turn a
// little about tilted axes and drift by up to 0.01: rigid motion (their RigidMotion set when
// `rigid`). With `wave`, a wave runs over the vertices every frame (radius 1 + 0.01 sin(...)):
// deforming meshes, new vertices every frame, the same topology. One phase.
std::unique_ptr<Sequence> make_crossing_spheres(int stacks, std::size_t frames, bool wave, bool rigid = true);

// A cloth folding onto itself over a ball (self-collision; kinematic, not a physical
// simulation): a sheet of 6 n^2 triangles folded over itself (make_folded_sheet(), core/primitives.h),
// its top layer sagging more and more through its bottom layer, descends onto a rigid ball that
// finally pokes through its bottom layer. The cloth is a deforming object with Object::self set
// (new vertices every frame); two phases: (a) falling and folding, (b) on the ball.
std::unique_ptr<Sequence> make_folding_cloth(int n, std::size_t frames, bool rigid = true);

// The torn cloth of test2 at tear fraction t in [0, 1]: an n x n grid over [-3, 3]^2 at height
// `y`, torn along x = 0.05 from z = -3 to z = -3 + 6t. Exposed for tests.
Mesh torn_cloth(int n, double t, double y);

}  // namespace peelcd
