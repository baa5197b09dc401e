// Containment and intersection volume on the classes of peelcd/eval/classes.h: every nested case
// reported inside (a collision without contact), no disjoint pair reported inside, volumes within
// their stated error of CGAL's exact volume and within 1% on deep overlaps, 0 on touching boxes;
// the World reports the same; an open mesh gets "unknown" and the reason.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/world/world.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/mesh_io.h"
#include "stride.h"  // PEELCD_TEST_STRIDE

#include <random>

#include <catch2/catch.hpp>
#include "fixtures.h"

using namespace peelcd;

namespace {
using test::cpu_detector;
}  // namespace

TEST_CASE("containment classes: the relation the construction gives, on both stages", "[containment]") {
  for (const ContainmentClass& c : containment_classes())
    for (const Stage stage : {Stage::automatic, Stage::image, Stage::exact}) {
      DetectOptions opt;
      opt.stage = stage;
      const ContainmentRow r = measure_containment(cpu_detector(), c, opt, 1);
      INFO(c.scene.name << ", stage " << to_string(stage) << ": found " << to_string(r.found));
      if (c.expected == Relation::disjoint) {
        CHECK((!r.pair || r.found == Relation::disjoint));
      } else {
        REQUIRE(r.pair);
        CHECK(r.found == c.expected);
      }
      // A nested pair is a collision with no contact.
      const FrameResult f = cpu_detector().detect(c.scene.objects, opt);
      if (c.expected == Relation::a_inside_b || c.expected == Relation::b_inside_a) {
        REQUIRE(f.pairs.size() == 1);
        CHECK(f.pairs[0].colliding.empty());
        CHECK(f.pairs[0].is_collision());
      }
    }
}

TEST_CASE("volume: within its error estimate of CGAL's exact volume, within 1% when deep, 0 when touching", "[containment][volume]") {
  DetectOptions opt;
  opt.volume = true;
  for (const ContainmentClass& c : containment_classes()) {
    const ContainmentRow r = measure_containment(cpu_detector(), c, opt, 1);
    INFO(c.scene.name << ": " << r.volume << " +- " << r.error_bound << ", exact " << r.exact_volume);
    if (!r.pair) continue;
    REQUIRE(r.volume_known);
    CHECK(r.error() <= r.error_bound + 1e-12 * std::max(1.0, r.exact_volume));
    if (r.exact_volume > 0.05 * r.smaller_volume) CHECK(r.relative_error() <= 0.01);
    if (c.expected == Relation::touching) {
      CHECK(r.volume == 0.0);
      CHECK(r.exact_volume == 0.0);
    }
  }
}

TEST_CASE("volume: the error estimate holds on random poses of closed meshes (CGAL's exact volume the reference)",
          "[containment][volume]") {
  // Poses of the kind where the estimate once did not hold (a kitten in a fish at 2.3x, a torus
  // and a kitten at 1.75x its estimate): B scaled to 0.6 of A's size, turned and moved at random.
  const std::string dir = std::string(PEELCD_FIXTURES) + "/meshes/";
  const std::pair<const char*, const char*> pairs[] = {{"kitten_1k5", "fish_2k"}, {"torus", "kitten_1k5"}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int frames = 0;
  for (const auto& [name_a, name_b] : pairs) {
    const Mesh a = load_mesh(dir + name_a + ".obj"), b0 = load_mesh(dir + name_b + ".obj");
    const Aabb ba = bounds(a), bb = bounds(b0);
    for (int f = 0; f < 30; ++f) {
      double r[7];
      for (double& x : r) x = u(rng);
      if (test::stride_skips(std::size_t(f))) continue;  // (after the draws: the kept poses are the same)
      Eigen::Affine3d pose = Eigen::Affine3d::Identity();
      pose.translate(0.5 * (ba.lo + ba.hi) + 0.25 * (ba.hi - ba.lo).norm() * Vec3(r[0], r[1], r[2]));
      pose.rotate(Eigen::AngleAxisd(3.14159265358979 * r[3], Vec3(r[4], r[5], r[6]).normalized()));
      pose.scale(0.6 * (ba.hi - ba.lo).norm() / (bb.hi - bb.lo).norm());
      pose.translate(-0.5 * (bb.lo + bb.hi));
      Mesh b = b0;
      for (Vec3& v : b.vertices) v = pose * v;
      double exact = 0.0;
      try {
        exact = exact_overlap_volume(a, b);
      } catch (const std::exception&) {
        continue;  // CGAL refused this pose: no reference
      }
      const VolumeEstimate e = overlap_volume(a, b, intersection(ba, bounds(b)), kVolumeResolution);
      INFO(name_a << " x " << name_b << " pose " << f << ": " << e.volume << " +- " << e.error << ", exact " << exact);
      REQUIRE(e.known);
      CHECK(std::abs(e.volume - exact) <= e.error);
      ++frames;
    }
  }
  CHECK(frames >= int(50 / test::stride()));
}

TEST_CASE("containment in the World: the same relations, rigid bodies moved by their poses", "[containment][world]") {
  for (const ContainmentClass& c : containment_classes()) {
    World world;
    std::vector<BodyId> ids;
    for (const Object& o : c.scene.objects) {
      // Translated shapes: the relation must come from the world positions.
      Mesh shape = o.mesh;
      for (Vec3& v : shape.vertices) v -= Vec3(5, 0, 0);
      Eigen::Affine3d pose = Eigen::Affine3d::Identity();
      pose.translate(Vec3(5, 0, 0));
      ids.push_back(world.add_rigid(std::make_shared<const Mesh>(std::move(shape)), pose, o.name));
    }
    const FrameResult& f = world.collide(DetectOptions{});
    INFO(c.scene.name);
    if (c.expected == Relation::disjoint) {
      CHECK(f.pairs.empty());
      continue;
    }
    REQUIRE(f.pairs.size() == 1);
    CHECK(f.pairs[0].relation == c.expected);
  }
}

TEST_CASE("an open container: relation unknown and volume unknown, each with the reason", "[containment]") {
  std::vector<Object> objects(2);
  objects[0].name = "ball";
  objects[0].mesh = uv_sphere(Vec3(0, 0, 0), 0.3, 12, 6);
  objects[1].name = "bowl";
  objects[1].mesh = uv_sphere(Vec3(0, 0, 0), 1.0, 24, 12);
  objects[1].mesh.triangles.resize(objects[1].mesh.triangles.size() / 2);  // open: the lower half
  // The ball's box lies within the bowl's only if the bowl's box covers it: the lower half's box
  // reaches z = 0 (the equator), the ball's z = +0.3: not within; move the ball down.
  for (Vec3& v : objects[0].mesh.vertices) v.z() -= 0.5;
  DetectOptions opt;
  opt.volume = true;
  const FrameResult f = cpu_detector().detect(objects, opt);
  REQUIRE(f.pairs.size() == 1);
  CHECK(f.pairs[0].relation == Relation::unknown);
  CHECK_THAT(f.pairs[0].relation_note, Catch::Contains("B is open"));
  CHECK_FALSE(f.pairs[0].volume.known);
  CHECK_THAT(f.pairs[0].volume.reason, Catch::Contains("B is open"));
  CHECK_FALSE(f.pairs[0].is_collision());
}
