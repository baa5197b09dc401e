#pragma once
// Classes of geometry a collision library meets, as small generated scenes: the accuracy of
// every configuration is measured and tested on each of them (docs/accuracy.md, "Per class";
// tests/eval/test_conservative_classes.cpp; peelcd classes). Every scene is built from closed-form meshes, so
// its exact contacts are what the construction says (axis-aligned faces, coincident surfaces,
// zero-area triangles, features thinner than a texel).
#include "peelcd/core/mesh.h"
#include "peelcd/core/exact/relation.h"

#include <string>
#include <vector>

namespace peelcd {

struct GeometryClass {
  std::string name;         // short, for tables and test names
  std::string description;  // what the scene is and why it is hard
  std::vector<Object> objects;
};

// Axis-aligned box, 8 corners, 12 triangles, outward-facing.
Mesh box_mesh(const Vec3& lo, const Vec3& hi);
// A flat grid of n x n quads (2n^2 triangles) at height z over [x0, x1] x [y0, y1]: an open
// surface.
Mesh floor_mesh(int n, double x0, double x1, double y0, double y1, double z);
// A UV sphere: `slices` around the z axis, `stacks` from pole to pole.
Mesh uv_sphere(const Vec3& center, double radius, int slices, int stacks);

// The built-in classes, in a fixed order:
//   crossing boxes, touching boxes, box on floor, coincident copy, degenerate triangles,
//   needle, open self-intersecting, crowded grid (grid_side^2 spheres in light contact).
std::vector<GeometryClass> geometry_classes(int grid_side = 10);

// Self-collision classes (docs/design.md, "Self-collision"): objects with Object::self set. A
// folded sheet whose top layer sags through the bottom, a closed tube tied in a trefoil whose
// strands cross, open unconnected pieces crossing (one object), three frames of a sheet folding
// onto itself, and a folded sheet crossing a ball (self and inter-object pairs together).
std::vector<GeometryClass> self_classes();

// Containment and volume classes (docs/design.md, "Containment and intersection volume"): two
// closed objects each, the relation their construction gives and, where it has one in closed
// form, the overlap volume (else CGAL's exact volume is the reference).
struct ContainmentClass {
  GeometryClass scene;
  Relation expected = Relation::disjoint;  // of the pair (object 0, object 1); disjoint: no pair
};
std::vector<ContainmentClass> containment_classes();

// Penetration depth classes (docs/design.md, "Penetration depth"): two closed objects each, and
// the depth their construction gives where it has one in closed form (-1: none; the exact
// property checks decide). Crossing boxes, deep spheres, a small object inside a large one, two
// concave rings crossing in two places, touching boxes (depth 0).
struct DepthClass {
  GeometryClass scene;
  double expected = -1.0;
};
std::vector<DepthClass> depth_classes();

// The sum of the lengths of the intersection segments of `pairs` (pack_pair(triA, triB)) of
// meshes `a` and `b`: the "intersection length" whose missed share docs/accuracy.md reports.
double intersection_length(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& pairs);

}  // namespace peelcd

#include "peelcd/core/image/detector.h"

namespace peelcd {

// One configuration measured on one class: every object pair's contacts scored against the
// exact reference (every miss counts), summed over the scene's pairs.
struct ClassRow {
  std::string class_name, config;
  std::size_t exact = 0, found = 0, missed = 0;
  std::size_t candidates = 0;  // triangle pairs given to the exact test
  double exact_length = 0.0, missed_length = 0.0;  // intersection length, world units
  double median_ms = 0.0;                          // FrameResult timings.total, median of the runs
  double miss_ratio() const { return exact ? double(missed) / double(exact) : 0.0; }
  double missed_length_share() const { return exact_length > 0 ? missed_length / exact_length : 0.0; }
};

// One containment class measured: the relation found against the expected one, and (options.volume)
// the volume estimate against CGAL's exact volume.
struct ContainmentRow {
  std::string class_name;
  Relation expected = Relation::disjoint, found = Relation::disjoint;
  bool pair = false;               // the boxes overlap: the frame has the pair
  bool volume_known = false;
  double volume = 0.0, error_bound = 0.0, exact_volume = 0.0;
  double error() const { return std::abs(volume - exact_volume); }
  double relative_error() const { return exact_volume > 0 ? error() / exact_volume : error(); }
  double smaller_volume = 0.0;     // the smaller object's volume (how deep the overlap is)
  double median_ms = 0.0;
};
ContainmentRow measure_containment(Detector& detector, const ContainmentClass& c, const DetectOptions& options, int repeat);

// Runs `options` on `g` with `detector` `repeat` times and scores the last frame.
ClassRow measure_class(Detector& detector, const GeometryClass& g, const std::string& config,
                       const DetectOptions& options, int repeat);

}  // namespace peelcd
