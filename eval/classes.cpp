#include "peelcd/eval/classes.h"

#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/primitives.h"

#include <cmath>
#include <cstdio>
#include <functional>

namespace peelcd {
namespace {

// Appends `m` to `into` (one object made of several pieces).
void append(Mesh& into, const Mesh& m) {
  const auto base = std::uint32_t(into.vertices.size());
  into.vertices.insert(into.vertices.end(), m.vertices.begin(), m.vertices.end());
  for (const Tri& t : m.triangles) into.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

Mesh moved(Mesh m, const Eigen::Affine3d& pose) {
  for (Vec3& v : m.vertices) v = pose * v;
  return m;
}


// A tube of radius `r` around the trefoil knot (x, y, z) = (sin t + 2 sin 2t, cos t - 2 cos 2t,
// -sin 3t): a closed mesh (a torus's topology); with r above about 0.61 (half the strands' closest distance) its strands pass through
// each other where the knot's curve passes close to itself.
Mesh knotted_tube(int along, int around, double r) {
  const auto curve = [](double t) {
    return Vec3(std::sin(t) + 2 * std::sin(2 * t), std::cos(t) - 2 * std::cos(2 * t), -std::sin(3 * t));
  };
  Mesh m;
  for (int i = 0; i < along; ++i) {
    const double t = 2 * M_PI * i / along;
    const Vec3 c = curve(t);
    const Vec3 tangent = (curve(t + 1e-4) - curve(t - 1e-4)).normalized();
    Vec3 n = tangent.cross(Vec3(0, 0, 1));
    if (n.norm() < 1e-6) n = tangent.cross(Vec3(1, 0, 0));
    n.normalize();
    const Vec3 b = tangent.cross(n);
    for (int k = 0; k < around; ++k) {
      const double a = 2 * M_PI * k / around;
      m.vertices.push_back(c + r * (std::cos(a) * n + std::sin(a) * b));
    }
  }
  const auto id = [&](int i, int k) { return std::uint32_t((i % along) * around + (k % around)); };
  for (int i = 0; i < along; ++i)
    for (int k = 0; k < around; ++k) {
      m.triangles.push_back({id(i, k), id(i + 1, k + 1), id(i + 1, k)});  // outward
      m.triangles.push_back({id(i, k), id(i, k + 1), id(i + 1, k + 1)});
    }
  return m;
}

Object self_object(std::string name, Mesh mesh) {
  Object o = named_object(std::move(name), std::move(mesh));
  o.self = true;
  return o;
}

}  // namespace

std::vector<GeometryClass> self_classes() {
  std::vector<GeometryClass> out;
  Eigen::Affine3d tilt = Eigen::Affine3d::Identity();
  tilt.rotate(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  out.push_back({"self: folded sheet",
                 "a sheet folded over itself, its top layer sagging through the bottom one (open, one object)",
                 {self_object("cloth", moved(make_folded_sheet(24, 0.1, 0.2), tilt))}});
  out.push_back({"self: knotted tube",
                 "a closed tube tied in a trefoil, thick enough that its strands pass through each other",
                 {self_object("knot", moved(knotted_tube(120, 12, 0.75), tilt))}});
  {
    // Two crossing open sheets and an open tube (no caps) through both, as one object: its
    // pieces share no vertex, so every crossing is a self pair.
    Mesh m = floor_mesh(6, -1, 1, -1, 1, 0.1);
    Eigen::Affine3d up = Eigen::Affine3d::Identity();
    up.rotate(Eigen::AngleAxisd(M_PI / 2, Vec3(1, 0, 0)));
    append(m, moved(floor_mesh(6, -1, 1, -1, 1, 0.05), up));
    append(m, make_grid_surface(16, 4, [](double u, double v) {
             const double a = 2 * M_PI * u;
             return Vec3(0.3 + 0.25 * std::cos(a), 0.2 + 0.25 * std::sin(a), -0.8 + 1.6 * v);
           }));
    out.push_back({"self: open pieces crossing",
                   "two crossing open sheets and an open tube through both, one object (open, unconnected pieces)",
                   {self_object("pieces", moved(m, tilt))}});
  }
  for (const double t : {0.6, 0.8, 1.0}) {
    // A sheet folding over frames: the frame at time t of a fold whose top layer sinks through
    // the bottom one as t grows (the deforming case; peelcd simulate --scene cloth runs it).
    char name[64];
    std::snprintf(name, sizeof name, "self: folding sheet t=%.1f", t);
    out.push_back({name, "frame t of a sheet folding onto itself and sagging through (deforming over frames)",
                   {self_object("cloth", moved(make_folded_sheet(20, 0.3 * (1.2 - t), 0.4 * t), tilt))}});
  }
  // Beside another object: the self pairs and the inter-object pairs of a frame together.
  out.push_back({"self: fold on a ball", "a folded sheet through itself lying on a ball it also crosses",
                 {self_object("cloth", moved(make_folded_sheet(20, 0.1, 0.2), tilt)),
                  named_object("ball", uv_sphere(tilt * Vec3(0.5, 0.5, -0.25), 0.3, 24, 12))}});
  return out;
}

namespace {
}  // namespace

// A torus in the plane z = c.z(): `along` segments around the ring of radius R, `around` around the
// tube of radius r; closed, outward.
Mesh torus(const Vec3& c, double R, double r, int along, int around) {
  Mesh m;
  for (int j = 0; j < around; ++j)
    for (int i = 0; i < along; ++i) {
      const double a = 2 * M_PI * i / along, b = 2 * M_PI * j / around;
      m.vertices.push_back(Vec3(c.x() + (R + r * std::cos(b)) * std::cos(a), c.y() + (R + r * std::cos(b)) * std::sin(a),
                                c.z() + r * std::sin(b)));
    }
  const auto id = [&](int i, int j) { return std::uint32_t((j % around) * along + (i % along)); };
  for (int j = 0; j < around; ++j)
    for (int i = 0; i < along; ++i) {  // d/da x d/db points out of the tube
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

std::vector<DepthClass> depth_classes() {
  std::vector<DepthClass> out;
  const auto two = [](const char* name, const char* what, Mesh a, Mesh b, double expected) {
    DepthClass c;
    c.scene = {name, what, {named_object("a", std::move(a)), named_object("b", std::move(b))}};
    c.expected = expected;
    return c;
  };
  out.push_back(two("crossing boxes", "a unit cube and a bar through its side, 0.3 deep: out along -x",
                    box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1)), box_mesh(Vec3(0.7, 0.2, 0.3), Vec3(3, 0.8, 0.6)), 0.3));
  out.push_back(two("deep spheres", "two spheres, radii 1 and 0.8, centres 0.5 apart: out along their centres",
                    uv_sphere(Vec3(0, 0, 0), 1.0, 48, 24), uv_sphere(Vec3(0.4, 0.3, 0.0), 0.8, 48, 24), -1.0));
  out.push_back(two("small inside large", "a small box wholly inside a large ball, off centre: out the nearer side",
                    box_mesh(Vec3(0.3, -0.1, -0.1), Vec3(0.5, 0.1, 0.1)), uv_sphere(Vec3(0, 0, 0), 1.0, 48, 24), -1.0));
  out.push_back(two("concave rings", "two tori in one plane, crossing in two places (not linked): lifted off",
                    torus(Vec3(0, 0, 0), 2.0, 0.5, 64, 16), torus(Vec3(2.5, 0.3, 0.1), 2.0, 0.5, 64, 16), -1.0));
  out.push_back(two("touching boxes", "two unit cubes sharing a face: depth 0",
                    box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1)), box_mesh(Vec3(1, 0.2, 0.1), Vec3(2, 0.9, 1.3)), 0.0));
  return out;
}

std::vector<ContainmentClass> containment_classes() {
  std::vector<ContainmentClass> out;
  const auto two = [](const char* name, const char* what, Mesh a, Mesh b, Relation r) {
    ContainmentClass c;
    c.scene = {name, what, {named_object("a", std::move(a)), named_object("b", std::move(b))}};
    c.expected = r;
    return c;
  };
  out.push_back(two("nested spheres", "a ball wholly inside a larger one, off centre: no surface contact",
                    uv_sphere(Vec3(0.2, 0.1, 0.0), 0.5, 24, 12), uv_sphere(Vec3(0, 0, 0), 1.0, 48, 24),
                    Relation::a_inside_b));
  out.push_back(two("inside a concave mesh", "a small ball inside a knotted tube (concave, genus 1), the tube as A",
                    knotted_tube(120, 16, 0.5), uv_sphere(Vec3(0, -1, 0), 0.25, 24, 12), Relation::b_inside_a));
  out.push_back(two("deep sphere overlap", "two spheres whose overlap is about half the smaller one",
                    uv_sphere(Vec3(0, 0, 0), 1.0, 48, 24), uv_sphere(Vec3(0.9, 0.2, 0.1), 0.8, 48, 24), Relation::crossing));
  out.push_back(two("boxes, known overlap", "two boxes overlapping in a 0.5 x 0.5 x 0.4 box (volume 0.1)",
                    box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1)), box_mesh(Vec3(0.5, 0.25, -1), Vec3(2, 0.75, 0.4)),
                    Relation::crossing));
  out.push_back(two("touching boxes, volume 0", "two unit boxes sharing a face: touching, no overlap volume",
                    box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1)), box_mesh(Vec3(1, 0, 0), Vec3(2, 1, 1)), Relation::touching));
  out.push_back(two("disjoint boxes 2e-4 apart", "two unit boxes 2e-4 apart: no pair, nothing inside",
                    box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1)), box_mesh(Vec3(1.0002, 0, 0), Vec3(2, 1, 1)), Relation::disjoint));
  return out;
}

Mesh box_mesh(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])});
    m.triangles.push_back({std::uint32_t(q[0]), std::uint32_t(q[2]), std::uint32_t(q[3])});
  }
  return m;
}

Mesh floor_mesh(int n, double x0, double x1, double y0, double y1, double z) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * j / n, z);
  const auto at = [n](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

Mesh uv_sphere(const Vec3& c, double r, int slices, int stacks) {
  Mesh m;
  m.vertices.push_back(c + Vec3(0, 0, -r));
  for (int s = 1; s < stacks; ++s) {
    const double phi = -M_PI / 2 + M_PI * s / stacks;
    for (int k = 0; k < slices; ++k) {
      const double th = 2 * M_PI * k / slices;
      m.vertices.push_back(c + r * Vec3(std::cos(phi) * std::cos(th), std::cos(phi) * std::sin(th), std::sin(phi)));
    }
  }
  m.vertices.push_back(c + Vec3(0, 0, r));
  const auto ring = [slices](int s, int k) { return std::uint32_t(1 + (s - 1) * slices + (k % slices)); };
  const auto top = std::uint32_t(m.vertices.size() - 1);
  for (int k = 0; k < slices; ++k) {
    m.triangles.push_back({0, ring(1, k + 1), ring(1, k)});
    for (int s = 1; s + 1 < stacks; ++s) {
      m.triangles.push_back({ring(s, k), ring(s, k + 1), ring(s + 1, k + 1)});
      m.triangles.push_back({ring(s, k), ring(s + 1, k + 1), ring(s + 1, k)});
    }
    m.triangles.push_back({ring(stacks - 1, k), ring(stacks - 1, k + 1), top});
  }
  return m;
}

std::vector<GeometryClass> geometry_classes(int grid_side) {
  std::vector<GeometryClass> out;
  // A generic rotation, for the scenes that must not be axis-aligned.
  Eigen::Affine3d tilt = Eigen::Affine3d::Identity();
  tilt.rotate(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));

  out.push_back({"crossing boxes",
                 "two axis-aligned boxes, a bar through a cube: every face edge-on along a world axis",
                 {named_object("cube", box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1))),
                  named_object("bar", box_mesh(Vec3(-2, -0.3, -0.4), Vec3(2, 0.5, 0.3)))}});
  out.push_back({"touching boxes", "two boxes face to face: coincident faces, no penetration",
                 {named_object("left", box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1))),
                  named_object("right", box_mesh(Vec3(1, 0.25, 0.25), Vec3(2, 1.25, 1.25)))}});
  out.push_back({"box on floor",
                 "a box resting on a tessellated floor (coincident faces) and a ball sunk into it",
                 {named_object("floor", floor_mesh(20, -2, 2, -2, 2, 0)),
                  named_object("box", box_mesh(Vec3(-0.5, -0.5, 0), Vec3(0.5, 0.5, 1))),
                  named_object("ball", uv_sphere(Vec3(1.2, 1.1, 0.25), 0.4, 24, 12))}});
  {
    const Mesh s = moved(uv_sphere(Vec3(0, 0, 0), 1.0, 48, 24), tilt);
    out.push_back({"coincident copy", "a mesh and its copy at the same pose: every surface coincident",
                   {named_object("sphere", s), named_object("copy", s)}});
  }
  {
    // Zero-area triangles: segments (a, b, b) and collinear triples through the cube's faces, and
    // points (p, p, p) on them; the exact test treats them as the segment or point they are.
    Mesh d;
    for (int i = 0; i < 8; ++i) {
      const double y = -0.8 + 0.2 * i, z = 0.7 - 0.17 * i;
      const auto base = std::uint32_t(d.vertices.size());
      d.vertices.emplace_back(0.5, y, z);
      d.vertices.emplace_back(1.5, y + 0.05, z - 0.03);
      d.vertices.emplace_back(1.0, y + 0.025, z - 0.015);  // on the segment: collinear
      d.triangles.push_back({base, base + 1, base + 1});
      d.triangles.push_back({base, base + 1, base + 2});
      const auto p = std::uint32_t(d.vertices.size());
      d.vertices.emplace_back(-0.6 + 0.15 * i, 1.0, 0.3 - 0.1 * i);  // a point on the face y = 1
      d.triangles.push_back({p, p, p});
    }
    out.push_back({"degenerate triangles", "segments, collinear triples and points crossing or lying on a cube's faces",
                   {named_object("cube", moved(box_mesh(Vec3(-1, -1, -1), Vec3(1, 1, 1)), tilt)),
                    named_object("slivers", moved(d, tilt))}});
  }
  {
    Mesh needle = box_mesh(Vec3(-1.5, 0.3, 0.2), Vec3(1.5, 0.3001, 0.2001));
    out.push_back({"needle", "a needle 1e-4 wide through a sphere: thinner than any texel",
                   {named_object("sphere", uv_sphere(Vec3(0, 0, 0), 1.0, 32, 16)), named_object("needle", needle)}});
  }
  {
    // Two perpendicular open sheets crossing each other (self-intersecting, open) and an open
    // half sphere through both.
    Mesh sheets = floor_mesh(6, -1, 1, -1, 1, 0.1);
    Eigen::Affine3d up = Eigen::Affine3d::Identity();
    up.rotate(Eigen::AngleAxisd(M_PI / 2, Vec3(1, 0, 0)));
    append(sheets, moved(floor_mesh(6, -1, 1, -1, 1, 0.05), up));
    Mesh half = uv_sphere(Vec3(0.3, 0.2, 0.0), 0.7, 24, 12);
    half.triangles.resize(half.triangles.size() / 2);  // the lower half: open along the equator
    out.push_back({"open self-intersecting", "two crossing open sheets (one object) and an open half sphere",
                   {named_object("sheets", moved(sheets, tilt)), named_object("half sphere", moved(half, tilt))}});
  }
  {
    GeometryClass g{"crowded grid",
                    std::to_string(grid_side * grid_side) +
                        " spheres in a grid, each overlapping its neighbours by 1% of its diameter",
                    {}};
    for (int j = 0; j < grid_side; ++j)
      for (int i = 0; i < grid_side; ++i)
        g.objects.push_back(named_object("ball " + std::to_string(j * grid_side + i),
                                   uv_sphere(Vec3(0.99 * i, 0.99 * j, 0.01 * ((i * 7 + j * 3) % 5)), 0.5, 16, 8)));
    out.push_back(std::move(g));
  }
  return out;
}

double intersection_length(const Mesh& a, const Mesh& b, const std::vector<std::uint64_t>& pairs) {
  double total = 0.0;
  for (const std::uint64_t k : pairs) {
    const auto [p, q] = intersection_segment(corners(a, pair_a(k)), corners(b, pair_b(k)));
    total += (q - p).norm();
  }
  return total;
}

}  // namespace peelcd

#include "peelcd/core/exact/reference.h"

#include <algorithm>

namespace peelcd {

ClassRow measure_class(Detector& detector, const GeometryClass& g, const std::string& config,
                       const DetectOptions& options, int repeat) {
  ClassRow row;
  row.class_name = g.name;
  row.config = config;
  FrameResult result;
  std::vector<double> ms;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    detector.detect(g.objects, options, result);
    ms.push_back(result.timings.total);
  }
  std::sort(ms.begin(), ms.end());
  row.median_ms = ms[ms.size() / 2];
  for (const PairResult& p : result.pairs) row.candidates += p.candidates;
  // Every pair of objects whose boxes overlap (no other pair can touch), also those the frame
  // culled away.
  std::vector<Aabb> boxes;
  for (const Object& o : g.objects) boxes.push_back(bounds(o.mesh));
  // With self-collision asked (Object::self or DetectOptions::self), each such object's self
  // pairs against the exact self reference too.
  for (std::size_t ia = 0; ia < g.objects.size(); ++ia)
    for (std::size_t ib = ia; ib < g.objects.size(); ++ib) {
      const bool self = ia == ib;
      if (self && !(options.self || g.objects[ia].self)) continue;
      if (!self && intersection(boxes[ia], boxes[ib]).empty()) continue;
      const Mesh& a = g.objects[ia].mesh;
      const Mesh& b = g.objects[ib].mesh;
      const std::vector<std::uint64_t> exact = exact_pair_reference(g.objects, ia, ib, options.self_adjacency);
      if (exact.empty()) continue;
      std::vector<Contact> reported;
      for (const PairResult& p : result.pairs)
        if (p.object_a == ia && p.object_b == ib) reported = p.colliding;
      const Score s = score_contacts(exact, reported);
      row.exact += s.exact;
      row.found += s.found;
      row.missed += s.missed;
      std::vector<std::uint64_t> found;
      for (const Contact& c : reported) found.push_back(pack_pair(c.tri_a, c.tri_b));
      std::sort(found.begin(), found.end());
      std::vector<std::uint64_t> missed;
      std::set_difference(exact.begin(), exact.end(), found.begin(), found.end(), std::back_inserter(missed));
      row.exact_length += intersection_length(a, b, exact);
      row.missed_length += intersection_length(a, b, missed);
    }
  return row;
}

}  // namespace peelcd

namespace peelcd {

ContainmentRow measure_containment(Detector& detector, const ContainmentClass& c, const DetectOptions& options, int repeat) {
  ContainmentRow row;
  row.class_name = c.scene.name;
  row.expected = c.expected;
  FrameResult result;
  std::vector<double> ms;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    detector.detect(c.scene.objects, options, result);
    ms.push_back(result.timings.total);
  }
  std::sort(ms.begin(), ms.end());
  row.median_ms = ms[ms.size() / 2];
  const Mesh& a = c.scene.objects[0].mesh;
  const Mesh& b = c.scene.objects[1].mesh;
  row.smaller_volume = std::min(analyse_shape(a).signed_volume, analyse_shape(b).signed_volume);
  for (const PairResult& p : result.pairs) {
    if (p.object_a != 0 || p.object_b != 1) continue;
    row.pair = true;
    row.found = p.relation;
    row.volume_known = p.volume.known;
    row.volume = p.volume.volume;
    row.error_bound = p.volume.error;
  }
  if (options.volume && row.pair) row.exact_volume = exact_overlap_volume(a, b);
  return row;
}

}  // namespace peelcd
