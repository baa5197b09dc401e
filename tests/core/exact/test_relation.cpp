// Containment and intersection volume (peelcd/core/exact/relation.h): the shape of a mesh (closed,
// oriented, inside out), the exact point-in-mesh test, the relation of two objects, and the
// image-space volume against CGAL's exact corefinement.
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"

#include <catch2/catch.hpp>

#include <algorithm>

using namespace peelcd;

namespace {
Mesh inverted(Mesh m) {
  for (Tri& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}
}  // namespace

TEST_CASE("a mesh's shape: closed, oriented, outward, and open or inside-out named", "[relation]") {
  const Mesh box = make_box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  const MeshShape s = analyse_shape(box);
  CHECK(s.closed);
  CHECK(s.oriented);
  CHECK(s.signed_volume == Approx(6.0));
  CHECK(s.problem().empty());
  CHECK(s.component_vertex.size() == 1);
  CHECK_THAT(analyse_shape(inverted(box)).problem(), Catch::Contains("inside out"));
  Mesh open = box;
  open.triangles.pop_back();
  CHECK_THAT(analyse_shape(open).problem(), Catch::Contains("open: 3 boundary edges"));
  Mesh flipped = box;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  CHECK_THAT(analyse_shape(flipped).problem(), Catch::Contains("inconsistently oriented"));
  const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  CHECK(analyse_shape(sphere).problem().empty());
}

TEST_CASE("point in mesh: exact, also on a grid of points through vertices and edges", "[relation]") {
  const Mesh box = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  CHECK(point_inside(box, Vec3(0.5, 0.5, 0.5)));
  CHECK_FALSE(point_inside(box, Vec3(1.5, 0.5, 0.5)));
  CHECK_FALSE(point_inside(box, Vec3(0.5, 0.5, -0.5)));
  // Points under the box's diagonal edges and corners (rays through shared edges and vertices).
  CHECK(point_inside(box, Vec3(0.5, 0.5, 0.25)));
  CHECK(point_inside(box, Vec3(0.25, 0.25, 0.1)));
  CHECK_FALSE(point_inside(box, Vec3(0.0 - 1e-9, 0.5, 0.5)));
  const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  int wrong = 0;
  for (int i = -6; i <= 6; ++i)
    for (int j = -6; j <= 6; ++j)
      for (int k = -6; k <= 6; ++k) {
        const Vec3 p(i / 5.0, j / 5.0, k / 5.0);
        if (std::abs(p.norm() - 1.0) < 0.05) continue;  // near the faceted surface
        wrong += point_inside(sphere, p) != (p.norm() < 1.0);
      }
  CHECK(wrong == 0);
}

TEST_CASE("relation: crossing, touching, inside either way, disjoint, unknown for an open container", "[relation]") {
  const Mesh big = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const Mesh small = make_uv_sphere(Vec3(0.1, 0.2, 0.0), 0.3, 8, 16);
  std::string note;
  CHECK(relate(small, big, {}, note) == Relation::a_inside_b);
  CHECK(relate(big, small, {}, note) == Relation::b_inside_a);
  const Mesh far = make_uv_sphere(Vec3(0.5, 0.5, 0.5), 0.1, 8, 16);  // box within, ball outside? inside
  CHECK(relate(far, big, {}, note) == Relation::a_inside_b);
  const Mesh corner = make_box(Vec3(0.8, 0.8, 0.8), Vec3(0.9, 0.9, 0.9));  // in the box, outside the ball
  CHECK(relate(corner, big, {}, note) == Relation::disjoint);
  Mesh open = big;
  open.triangles.resize(open.triangles.size() / 2);
  CHECK(relate(small, open, {}, note) == Relation::unknown);
  CHECK_THAT(note, Catch::Contains("B is open"));
  Contact touch;
  touch.kind = ContactKind::touching;
  CHECK(relate(small, big, {touch}, note) == Relation::touching);
  Contact cross;
  CHECK(relate(small, big, {touch, cross}, note) == Relation::crossing);
}

TEST_CASE("volume: boxes exact (error one texel column), spheres within the stated error of CGAL's exact volume", "[relation][volume]") {
  const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = make_box(Vec3(0.5, 0.25, -1), Vec3(2, 0.75, 0.4));
  const Aabb roi = intersection(bounds(a), bounds(b));
  const VolumeEstimate e = overlap_volume(a, b, roi, 64);
  REQUIRE(e.known);
  CHECK(e.volume == Approx(0.5 * 0.5 * 0.4).epsilon(1e-12));
  // Every cast agrees: the error is the floor, one texel column of the z cast.
  CHECK(e.error == Approx(0.5 * 0.5 * 0.4 / (64.0 * 64.0)).epsilon(1e-9));
  // The overlap grows moving A along +x (B lies that way): the gradient's x is positive.
  CHECK(e.gradient.x() == Approx(0.5 * 0.4).epsilon(1e-9));
  CHECK(exact_overlap_volume(a, b) == Approx(0.1).epsilon(1e-12));
  // A piece of B far outside the overlap box (1e25 away) changes nothing (and converts no huge
  // coordinate to a texel index).
  Mesh far = b;
  const Mesh piece = make_box(Vec3(1e25, -1e25, 3e24), Vec3(1e25 + 1, -1e25 + 1, 3e24 + 1));
  const auto base = std::uint32_t(far.vertices.size());
  far.vertices.insert(far.vertices.end(), piece.vertices.begin(), piece.vertices.end());
  for (const Tri& t : piece.triangles) far.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  CHECK(overlap_volume(a, far, roi, 64).volume == Approx(0.1).epsilon(1e-12));

  const Mesh s1 = make_uv_sphere(Vec3(0, 0, 0), 1.0, 24, 48);
  const Mesh s2 = make_uv_sphere(Vec3(0.9, 0.2, 0.1), 0.8, 24, 48);
  const VolumeEstimate v = overlap_volume(s1, s2, intersection(bounds(s1), bounds(s2)), 256);
  const double exact = exact_overlap_volume(s1, s2);
  INFO("estimate " << v.volume << " +- " << v.error << ", exact " << exact);
  CHECK(std::abs(v.volume - exact) <= v.error);
  CHECK(std::abs(v.volume - exact) <= 0.01 * exact);
  CHECK(v.gradient.x() > 0);  // moving A (the left sphere) towards B (+x) grows the overlap
  // Open or inside-out: no number, the reason.
  const VolumeEstimate bad = overlap_volume(inverted(s1), s2, intersection(bounds(s1), bounds(s2)), 64);
  CHECK_FALSE(bad.known);
  CHECK_THAT(bad.reason, Catch::Contains("A is inside out"));
}

TEST_CASE("face, edge and corner contact of boxes is touching, and a box touching a box from inside is inside: CGAL's volumes agree",
          "[relation]") {
  // Every contact kind and the relation decided exactly, on the exact CPU path, against CGAL's
  // exact overlap volume: 0 for touching boxes, the inner box's for one inside.
  Detector detector(std::make_shared<CpuImageStage>());
  DetectOptions opt;
  opt.stage = Stage::exact;
  const Mesh unit = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const auto frame = [&](const Mesh& a, const Mesh& b) {
    std::vector<Object> objects(2);
    objects[0].mesh = a;
    objects[1].mesh = b;
    const FrameResult f = detector.detect(objects, opt);
    REQUIRE(f.pairs.size() == 1);
    return f.pairs[0];
  };
  // Face to face with offset faces, along an edge, at a corner: touching, no crossing contact.
  for (const Vec3& offset : {Vec3(1, 0.5, 0.25), Vec3(1, 0.3, 0.7), Vec3(1, -0.25, 0.5), Vec3(1, 1, 0), Vec3(1, 1, 1),
                             Vec3(1, 0.5, 1)}) {
    const Mesh moved = make_box(offset, offset + Vec3(1, 1, 1));
    const PairResult p = frame(unit, moved);
    INFO("offset " << offset.transpose());
    CHECK(exact_overlap_volume(unit, moved) == 0.0);
    CHECK_FALSE(p.colliding.empty());
    for (const Contact& c : p.colliding) CHECK(c.kind != ContactKind::crossing);
    CHECK(p.relation == Relation::touching);
  }
  // A unit box inside a box of side 2, sharing one face: inside (volume 1), not touching.
  const Mesh big = make_box(Vec3(0, 0, 0), Vec3(2, 2, 2));
  const Mesh inner = make_box(Vec3(1, 0.5, 0.5), Vec3(2, 1.5, 1.5));
  CHECK(exact_overlap_volume(big, inner) == Approx(1.0));
  const PairResult in = frame(big, inner);
  CHECK(in.relation == Relation::b_inside_a);
  CHECK(in.relation_note.find("from inside") != std::string::npos);
  CHECK(frame(inner, big).relation == Relation::a_inside_b);
  // A closed mesh and its copy at the same pose: one interior, so inside (not touching), from
  // either side; the copy with its triangles in another order and turned corners too.
  const Mesh ball = make_uv_sphere(Vec3(0.3, 0.2, 0.1), 1.0, 8, 16);
  Mesh shuffled = ball;
  std::reverse(shuffled.triangles.begin(), shuffled.triangles.end());
  for (Tri& t : shuffled.triangles) t = {t[1], t[2], t[0]};
  for (const Mesh* copy : std::initializer_list<const Mesh*>{&ball, &shuffled}) {
    const PairResult same = frame(ball, *copy);
    CHECK(same.relation == Relation::a_inside_b);
    CHECK(same.relation_note.find("coincide") != std::string::npos);
    CHECK(same.is_collision());
  }
  // One vertex of the copy moved off the surface: not one surface any more (not said to coincide).
  Mesh dented = ball;
  dented.vertices[5] *= 0.97;
  CHECK(frame(ball, dented).relation_note.find("coincide") == std::string::npos);
  // Moved out through that face by half: crossing, as before.
  CHECK(frame(big, make_box(Vec3(1.5, 0.5, 0.5), Vec3(2.5, 1.5, 1.5))).relation == Relation::crossing);
}
