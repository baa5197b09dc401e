// The public collision API through the CPU image stage (no GL): per-pair collide(), persistent
// rigid and deforming objects, the world, and the errors bad input gives.
#include "peelcd/core/world/collision.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/world/world.h"

#include "gated_stage.h"

#include <catch2/catch.hpp>

#include <condition_variable>
#include <mutex>
#include <thread>

using namespace peelcd;

namespace {

std::shared_ptr<Detector> cpu_detector() { return std::make_shared<Detector>(std::make_shared<CpuImageStage>()); }

Mesh moved(const Mesh& m, const Eigen::Affine3d& pose) {
  Mesh w = m;
  for (Vec3& v : w.vertices) v = pose * v;
  return w;
}

}  // namespace

TEST_CASE("collide(): two spheres, rigid objects and plain meshes agree and report only exact pairs", "[api]") {
  auto detector = cpu_detector();
  const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const auto geometry = std::make_shared<const CollisionGeometry>(sphere, "sphere");
  const Eigen::Affine3d pa = Eigen::Affine3d::Identity();
  const Eigen::Affine3d pb(Eigen::Translation3d(1.3, 0.4, 0.2) * Eigen::AngleAxisd(0.4, Vec3(0, 1, 0)));
  CollisionObject a(geometry, pa, "a"), b(geometry, pb, "b");
  CollisionRequest request;
  CollisionResult r1, r2;
  REQUIRE(collide(*detector, a, b, request, r1) > 0);
  REQUIRE(r1.is_collision());
  collide(*detector, sphere, pa, sphere, pb, request, r2);
  REQUIRE(r1.contacts.size() == r2.contacts.size());
  for (std::size_t i = 0; i < r1.contacts.size(); ++i) {
    CHECK(r1.contacts[i].tri_a == r2.contacts[i].tri_a);
    CHECK(r1.contacts[i].tri_b == r2.contacts[i].tri_b);
  }
  // Against the exact all-pairs reference: every reported pair is exact (a consistency check:
  // the narrow phase is exact), and the default configuration finds them all here.
  const Score s = score_contacts(exact_colliding_pairs(moved(sphere, pa), moved(sphere, pb)), r1.contacts);
  CHECK(s.false_contacts == 0);
  CHECK(s.missed == 0);
  // Moved apart: no contact, no pair.
  b.set_pose(Eigen::Affine3d(Eigen::Translation3d(5, 0, 0)));
  CHECK(collide(*detector, a, b, request, r1) == 0);
  CHECK_FALSE(r1.is_collision());
}

TEST_CASE("a deforming object is updated in place, without a copy of its mesh", "[api]") {
  auto detector = cpu_detector();
  CollisionObject ball = CollisionObject::deforming(make_uv_sphere(Vec3(0, 0, 0), 1.0, 10, 20), "ball");
  const auto geometry = std::make_shared<const CollisionGeometry>(make_box(Vec3(0.8, -0.5, -0.5), Vec3(2, 0.5, 0.5)));
  CollisionObject box(geometry, Eigen::Affine3d::Identity(), "box");
  CollisionWorld world(detector);
  world.add(&ball);
  world.add(&box);
  const Vec3* storage = ball.deforming_vertices().data();
  std::size_t touching = 0;
  for (int frame = 0; frame < 5; ++frame) {
    const double scale = 0.7 + 0.1 * frame;  // the ball grows into the box
    const Mesh rest = make_uv_sphere(Vec3(0, 0, 0), 1.0, 10, 20);
    for (std::size_t i = 0; i < rest.vertices.size(); ++i) ball.deforming_vertices()[i] = rest.vertices[i] * scale;
    const FrameResult& f = world.detect();
    CHECK(ball.deforming_vertices().data() == storage);   // the same vertex storage
    CHECK(&ball.world().mesh.vertices[0] == storage);     // the frame read it where it lies
    const std::size_t n = f.pairs.empty() ? 0 : f.pairs[0].colliding.size();
    if (scale <= 0.75) CHECK(n == 0);  // 0.7, 0.8 of radius: the box starts at x = 0.8
    if (scale >= 0.9) CHECK(n > 0);
    touching += n;
  }
  CHECK(touching > 0);
  CHECK_THROWS_AS(box.deforming_vertices(), std::logic_error);
  CHECK_THROWS_AS(ball.set_pose(Eigen::Affine3d::Identity()), std::logic_error);
}

TEST_CASE("bad meshes and poses give exceptions that name the object and the problem", "[api][nonfinite]") {
  auto detector = cpu_detector();
  Mesh bad_index = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  bad_index.triangles[3][1] = 99;
  CHECK_THROWS_WITH(CollisionGeometry(bad_index, "crate"),
                    Catch::Contains("'crate'") && Catch::Contains("triangle 3 uses vertex 99") &&
                        Catch::Contains("8 vertices"));
  Mesh nan_vertex = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  nan_vertex.vertices[5].y() = std::nan("");
  CHECK_THROWS_WITH(CollisionGeometry(nan_vertex, "crate"),
                    Catch::Contains("'crate'") && Catch::Contains("vertex 5 has a NaN or infinite coordinate"));
  Mesh inf_vertex = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  inf_vertex.vertices[2].z() = HUGE_VAL;
  CHECK_THROWS_WITH(CollisionGeometry(inf_vertex, "crate"), Catch::Contains("vertex 2 has a NaN or infinite"));

  // Through the detector: a deforming object turned bad between frames is refused, named.
  CollisionObject blob = CollisionObject::deforming(make_uv_sphere(Vec3(0, 0, 0), 1.0, 8, 16), "blob");
  CollisionObject other = CollisionObject::deforming(make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 8, 16), "other");
  CollisionRequest request;
  CollisionResult result;
  CHECK(collide(*detector, blob, other, request, result) > 0);
  blob.deforming_mesh().triangles[0][0] = 1000;
  CHECK_THROWS_WITH(collide(*detector, blob, other, request, result),
                    Catch::Contains("object 0 'blob'") && Catch::Contains("triangle 0 uses vertex 1000"));
  blob.deforming_mesh().triangles[0][0] = 0;
  blob.deforming_vertices()[0].x() = std::nan("");
  CHECK_THROWS_WITH(collide(*detector, blob, other, request, result),
                    Catch::Contains("object 0 'blob'") && Catch::Contains("NaN or infinite"));
  // A pose with infinities.
  const auto g = std::make_shared<const CollisionGeometry>(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), "g");
  CollisionObject rigid(g, Eigen::Affine3d::Identity(), "lid");
  Eigen::Affine3d inf_pose = Eigen::Affine3d::Identity();
  inf_pose.translation().x() = HUGE_VAL;
  CHECK_THROWS_WITH(rigid.set_pose(inf_pose), Catch::Contains("'lid'") && Catch::Contains("NaN or infinite"));
  // Impossible options name the option.
  request.options.resolution = 1 << 20;
  CHECK_THROWS_WITH(collide(*detector, rigid, other, request, result),
                    Catch::Contains("resolution") && Catch::Contains("1048576"));
}

using test::GatedStage;

TEST_CASE("one detector called from a second thread during a frame throws a clear error, no crash", "[api]") {
  auto stage = std::make_shared<GatedStage>();
  Detector detector(stage);
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 10, 20), b = make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 10, 20);
  std::vector<Object> objects(2);
  objects[0].mesh = a, objects[0].name = "a";
  objects[1].mesh = b, objects[1].name = "b";
  DetectOptions opt;
  opt.stage = Stage::image;  // the frame reaches the stage (and waits there)
  FrameResult first;
  std::thread owner([&] { detector.detect(objects, opt, first); });
  stage->wait_entered();
  FrameResult second;
  CHECK_THROWS_WITH(detector.detect(objects, opt, second),
                    Catch::Contains("peelcd::Detector: called from a second thread") && Catch::Contains("one per thread"));
  stage->release();
  owner.join();
  // The first frame completed untouched, and the detector is free again.
  CHECK(first.pairs.size() == 1);
  CHECK(!first.pairs[0].colliding.empty());
  detector.detect(objects, opt, second);
  CHECK(second.pairs[0].colliding.size() == first.pairs[0].colliding.size());
}

TEST_CASE("one World changed or run from a second thread during a frame throws a clear error, no crash", "[api]") {
  auto stage = std::make_shared<GatedStage>();
  World world(stage);
  const auto a = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 1.0, 10, 20));
  const auto b = std::make_shared<const Mesh>(make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 10, 20));
  const BodyId ia = world.add_rigid(a, Eigen::Affine3d::Identity(), "a");
  world.add_rigid(b, Eigen::Affine3d::Identity(), "b");
  DetectOptions opt;
  opt.stage = Stage::image;  // the frame reaches the stage (and waits there)
  FrameResult first;
  std::thread owner([&] { world.collide(opt, first); });
  stage->wait_entered();
  FrameResult second;
  // (Catch's combined matchers hold their parts by reference: one built per check.)
#define PEELCD_WORLD_REFUSED Catch::Contains("peelcd::World: called from a second thread") && Catch::Contains("one per thread")
  CHECK_THROWS_WITH(world.collide(opt, second), PEELCD_WORLD_REFUSED);
  CHECK_THROWS_WITH(world.set_pose(ia, Eigen::Affine3d(Eigen::Translation3d(5, 0, 0))), PEELCD_WORLD_REFUSED);
  CHECK_THROWS_WITH(world.remove(ia), PEELCD_WORLD_REFUSED);
  CHECK_THROWS_WITH(world.add_rigid(a, Eigen::Affine3d::Identity()), PEELCD_WORLD_REFUSED);
#undef PEELCD_WORLD_REFUSED
  stage->release();
  owner.join();
  // The first frame completed untouched (nothing was moved or removed), and the World is free again.
  CHECK(first.pairs.size() == 1);
  CHECK(!first.pairs[0].colliding.empty());
  CHECK(world.size() == 2);
  world.collide(opt, second);
  CHECK(second.pairs[0].colliding.size() == first.pairs[0].colliding.size());
}

TEST_CASE("messages name the right argument (collide(Mesh...)'s b and its poses) and a zero-scale pose is refused",
          "[api]") {
  auto detector = cpu_detector();
  const Mesh good = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  Mesh bad = good;
  bad.vertices[3].x() = std::nan("");
  CollisionRequest request;
  CollisionResult result;
  const Eigen::Affine3d I = Eigen::Affine3d::Identity();
  CHECK_THROWS_WITH(collide(*detector, good, I, bad, I, request, result),
                    Catch::Contains("'b'") && !Catch::Contains("object 0") && Catch::Contains("vertex 3"));
  CHECK_THROWS_WITH(collide(*detector, bad, I, good, I, request, result), Catch::Contains("'a'"));
  Eigen::Affine3d nan_pose = I;
  nan_pose.translation().y() = std::nan("");
  CHECK_THROWS_WITH(collide(*detector, good, I, good, nan_pose, request, result),
                    Catch::Contains("peelcd::collide(): pose_b") && !Catch::Contains("set_pose"));
  // A zero scale collapses the mesh to a point: refused where the pose is given, and by the detector.
  const auto g = std::make_shared<const CollisionGeometry>(good, "g");
  CollisionObject rigid(g, I, "lid");
  Eigen::Affine3d flat = I;
  flat.linear() *= 0.0;
  CHECK_THROWS_WITH(rigid.set_pose(flat), Catch::Contains("'lid'") && Catch::Contains("singular"));
  CHECK_THROWS_WITH(collide(*detector, good, I, good, flat, request, result), Catch::Contains("pose_b is singular"));
}

TEST_CASE("coordinates beyond float range: refused by any frame that may use the image stage, exact path exact",
          "[api]") {
  const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const Mesh other = make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.9, 12, 24);
  const auto with_far_vertex = [&](double far) {
    Mesh m = sphere;
    m.vertices.back() = Vec3(0, 0, far);  // the pole: stretched into a long spike
    return m;
  };
  const Eigen::Affine3d I = Eigen::Affine3d::Identity();
  CollisionRequest request;
  CollisionResult result;
  for (const double far : {1e38, 3.4e38}) {  // within float range: every exact pair found
    INFO("far vertex at z = " << far);
    const Mesh a = with_far_vertex(far);
    const std::vector<std::uint64_t> exact = exact_colliding_pairs(a, other);
    REQUIRE(!exact.empty());
    for (const Stage stage : {Stage::image, Stage::exact, Stage::automatic}) {
      auto detector = cpu_detector();
      request.options.stage = stage;
      collide(*detector, a, I, other, I, request, result);
      CHECK(score_contacts(exact, result.contacts).missed == 0);
    }
  }
  for (const double far : {1e39, 1e155, 1e300}) {
    INFO("far vertex at z = " << far);
    const Mesh a = with_far_vertex(far);
    auto detector = cpu_detector();
    for (const Stage stage : {Stage::image, Stage::automatic}) {
      request.options.stage = stage;
      CHECK_THROWS_WITH(collide(*detector, a, I, other, I, request, result),
                        Catch::Contains("'a'") && Catch::Contains("outside the float range (|x| <= 3.4e38)"));
    }
    request.options.stage = Stage::exact;  // the exact CPU path takes every finite double
    collide(*detector, a, I, other, I, request, result);
    CHECK(score_contacts(exact_colliding_pairs(a, other), result.contacts).missed == 0);
  }
}

TEST_CASE("is_collision() is true for a closed object inside another, with no contact", "[api]") {
  auto detector = cpu_detector();
  const Mesh outer = make_box(Vec3(-1, -1, -1), Vec3(1, 1, 1)), inner = make_box(Vec3(-0.2, -0.2, -0.2), Vec3(0.2, 0.2, 0.2));
  CollisionRequest request;
  CollisionResult result;
  CHECK(collide(*detector, inner, Eigen::Affine3d::Identity(), outer, Eigen::Affine3d::Identity(), request, result) == 0);
  CHECK(result.contacts.empty());
  CHECK(result.pair.relation == Relation::a_inside_b);
  CHECK(result.is_collision());
  // Moved out of the box, apart: no collision.
  collide(*detector, inner, Eigen::Affine3d(Eigen::Translation3d(5, 0, 0)), outer, Eigen::Affine3d::Identity(), request,
          result);
  CHECK_FALSE(result.is_collision());
}

TEST_CASE("max_contacts: a first-contact query stops at N contacts, on both paths and in the World", "[api]") {
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32), b = make_uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 16, 32);
  std::vector<Object> objects(2);
  objects[0].mesh = a;
  objects[1].mesh = b;
  const std::vector<std::uint64_t> exact = exact_colliding_pairs(a, b);
  REQUIRE(exact.size() > 10);
  Detector detector(std::make_shared<CpuImageStage>());
  for (const Stage stage : {Stage::exact, Stage::image})
    for (const std::size_t n : {std::size_t(1), std::size_t(5)}) {
      DetectOptions opt;
      opt.stage = stage;
      opt.max_contacts = n;
      const FrameResult f = detector.detect(objects, opt);
      INFO(to_string(stage) << ", max_contacts " << n);
      REQUIRE(f.pairs.size() == 1);
      CHECK(f.pairs[0].colliding.size() == n);
      CHECK(f.pairs[0].is_collision());
      CHECK(f.pairs[0].relation_note.find("max_contacts") != std::string::npos);
      for (const Contact& c : f.pairs[0].colliding)  // each one a true contact
        CHECK(std::binary_search(exact.begin(), exact.end(), pack_pair(c.tri_a, c.tri_b)));
    }
  World world;
  world.add_rigid(std::make_shared<const Mesh>(a), Eigen::Affine3d::Identity());
  world.add_rigid(std::make_shared<const Mesh>(b), Eigen::Affine3d::Identity());
  DetectOptions opt;
  opt.max_contacts = 1;
  CHECK(world.collide(opt).pairs.at(0).colliding.size() == 1);
  opt.max_contacts = 0;  // every contact again
  CHECK(world.collide(opt).pairs.at(0).colliding.size() == exact.size());
}
