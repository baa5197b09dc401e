#pragma once
// What a frame says about an object pair beyond its contacts (PairResult): how the two objects
// relate (peelcd/core/exact/relation.h), their intersection volume, a penetration depth
// (peelcd/core/exact/depth.h) and the triangle pairs within a margin
// (peelcd/core/exact/proximity.h). Values only: the exact wing computes them.
#include "peelcd/core/mesh.h"

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace peelcd {

// disjoint, touching, crossing, or one wholly inside the other with no surface contact (a
// collision too); unknown where containment needs a closed container and there is none.
enum class Relation { disjoint, touching, crossing, a_inside_b, b_inside_a, unknown };
const char* to_string(Relation relation);  // "disjoint", "touching", "crossing", "a_inside_b", ...
// A relation is a collision unless disjoint or unknown.
inline bool colliding_relation(Relation r) { return r != Relation::disjoint && r != Relation::unknown; }

// The volume's error estimate: this many times the casts' largest difference (chosen on random
// frames of six closed mesh pairs against CGAL's exact volumes: docs/accuracy.md).
constexpr double kVolumeErrorFactor = 3.0;

struct VolumeEstimate {
  bool known = false;      // false: see `reason`
  std::string reason;      // why there is no number (an open mesh, inside out, ...)
  double volume = 0.0;     // world units cubed
  double error = 0.0;      // the error estimate: kVolumeErrorFactor times the largest difference
                           // between `volume` (z) and the x, y and half-resolution casts, at
                           // least one texel column (an estimate, not a proof: docs/design.md)
  Vec3 gradient = Vec3::Zero();  // d volume / d translation of A (move A along -gradient)
  int resolution = 0;      // texels across, per axis
  std::string method;      // how it was computed
};

struct PenetrationDepth {
  bool known = false;
  std::string reason;             // why unknown (an open or inside-out object), else empty
  Vec3 direction = Vec3::Zero();  // unit n: move A by depth * n (B fixed)
  double depth = 0.0;             // d >= 0; 0 when the objects only touch
  // Rounding bound of d: the least separating translation along n lies in [depth - 2 bound,
  // depth] (d errs toward separating).
  double bound = 0.0;
  std::size_t directions = 0;     // directions evaluated
  std::string source;             // the candidate the search started from ("contact normals of B", ...)
};

struct NearPair {
  std::uint32_t tri_a = 0, tri_b = 0;  // self pairs: tri_a < tri_b
  double distance = 0.0;
  Vec3 p = Vec3::Zero(), q = Vec3::Zero();  // the closest points, on A's and on B's triangle
};

struct Proximity {
  std::vector<NearPair> pairs;  // every pair within the margin, by (tri_a, tri_b)
  // The least distance of the pairs and its witness points (infinite, no points: none is within
  // the margin).
  double distance = std::numeric_limits<double>::infinity();
  Vec3 p = Vec3::Zero(), q = Vec3::Zero();
  bool within() const { return !pairs.empty(); }
};

}  // namespace peelcd
