// One thread at a time: every public entry of World, Detector and CollisionWorld refuses a second
// thread while a first is inside. The first thread is held inside a frame by an image stage that
// blocks in begin_frame() until the test has tried every entry from a second thread; then the
// first thread's frame completes, and its pairs are checked against the exact reference.
#include "peelcd/core/world/collision.h"
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/world/world.h"

#include "gated_stage.h"

#include <catch2/catch.hpp>

#include <functional>
#include <thread>

using namespace peelcd;

namespace {

using test::GatedStage;

// Runs `first` on a thread until it is inside the gate, calls each of `entries` from this
// thread (each must throw std::logic_error naming `what`), releases the gate and joins.
void refused_while_inside(GatedStage& gate, const std::function<void()>& first,
                          const std::vector<std::pair<const char*, std::function<void()>>>& entries, const char* what) {
  std::exception_ptr failed;
  std::thread t([&] {
    try {
      first();
    } catch (...) {
      failed = std::current_exception();
    }
  });
  gate.wait_entered();
  for (const auto& [name, call] : entries) {
    INFO(name);
    CHECK_THROWS_WITH(call(), Catch::Contains(std::string(what) + ": called from a second thread"));
  }
  gate.release();
  t.join();
  REQUIRE_FALSE(failed);
}

DetectOptions image_stage() {
  DetectOptions o;
  o.stage = Stage::image;
  return o;
}

}  // namespace

TEST_CASE("World: every public entry refuses a second thread while a frame runs", "[world][threads]") {
  const auto gate = std::make_shared<GatedStage>();
  World world(gate);
  const auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 12, 24));
  const Mesh other = make_uv_sphere(Vec3(1.2, 0.1, 0.05), 1.0, 12, 24);
  const BodyId a = world.add_rigid(ball, Eigen::Affine3d::Identity(), "a");
  const BodyId b = world.add_deforming(other, "b");
  const DetectOptions opt = image_stage();
  FrameResult first, out;
  const std::vector<std::pair<const char*, std::function<void()>>> entries = {
      {"add_rigid", [&] { world.add_rigid(ball, Eigen::Affine3d::Identity(), "c"); }},
      {"add_deforming", [&] { world.add_deforming(other, "d"); }},
      {"remove", [&] { world.remove(a); }},
      {"set_pose", [&] { world.set_pose(a, Eigen::Affine3d::Identity()); }},
      {"set_vertices (copy)", [&] { world.set_vertices(b, other.vertices); }},
      {"set_vertices (move)", [&] { world.set_vertices(b, std::vector<Vec3>(other.vertices)); }},
      {"move_vertices", [&] { world.move_vertices(b, {0u}, {other.vertices[0]}); }},
      {"set_mesh", [&] { world.set_mesh(b, other); }},
      {"set_shape", [&] { world.set_shape(a, ball); }},
      {"set_self", [&] { world.set_self(a, true); }},
      {"self", [&] { (void)world.self(a); }},
      {"contains", [&] { (void)world.contains(a); }},
      {"size", [&] { (void)world.size(); }},
      {"name", [&] { (void)world.name(a); }},
      {"find", [&] { (void)world.find("a"); }},
      {"rigid", [&] { (void)world.rigid(a); }},
      {"mesh", [&] { (void)world.mesh(a); }},
      {"world_mesh", [&] { (void)world.world_mesh(a); }},
      {"tree", [&] { (void)world.tree(a); }},
      {"collide (kept result)", [&] { (void)world.collide(opt); }},
      {"collide (out)", [&] { world.collide(opt, out); }},
      {"stats", [&] { (void)world.stats(); }},
      {"stage", [&] { (void)world.stage(); }},
      {"batch_image_pairs", [&] { world.batch_image_pairs(false); }},
  };
  refused_while_inside(*gate, [&] { world.collide(opt, first); }, entries, "peelcd::World");
  const Mesh world_a = world.world_mesh(a);
  REQUIRE(first.pairs.size() == 1);
  std::vector<std::uint64_t> got;
  for (const Contact& c : first.pairs[0].colliding) got.push_back(pack_pair(c.tri_a, c.tri_b));
  CHECK(got == exact_colliding_pairs(world_a, other));
  CHECK(world.size() == 2);  // nothing the refused calls asked for happened
  CHECK_FALSE(world.find("c"));
}

TEST_CASE("Detector and CollisionWorld: every public entry refuses a second thread", "[detector][threads]") {
  const Mesh ball = make_uv_sphere(Vec3::Zero(), 1.0, 12, 24);
  const Mesh other = make_uv_sphere(Vec3(1.2, 0.1, 0.05), 1.0, 12, 24);
  std::vector<Object> objects(2);
  objects[0].mesh = ball;
  objects[1].mesh = other;
  const std::vector<const Object*> ptrs = {&objects[0], &objects[1]};
  const DetectOptions opt = image_stage();
  {
    const auto gate = std::make_shared<GatedStage>();
    Detector detector(gate);
    FrameResult first, out;
    std::vector<CapturedView> sink;
    const std::vector<std::pair<const char*, std::function<void()>>> entries = {
        {"detect (value)", [&] { (void)detector.detect(objects, opt); }},
        {"detect (out)", [&] { detector.detect(objects, opt, out); }},
        {"detect (pointers)", [&] { detector.detect(ptrs, opt, out); }},
        {"only_pairs", [&] { detector.only_pairs(nullptr); }},
        {"capture_layers", [&] { detector.capture_layers(&sink); }},
        {"for_each_view", [&] { detector.for_each_view(objects, opt, [](const PeelJob&) {}); }},
    };
    refused_while_inside(*gate, [&] { detector.detect(objects, opt, first); }, entries, "peelcd::Detector");
    REQUIRE(first.pairs.size() == 1);
    std::vector<std::uint64_t> got;
    for (const Contact& c : first.pairs[0].colliding) got.push_back(pack_pair(c.tri_a, c.tri_b));
    CHECK(got == exact_colliding_pairs(ball, other));
  }
  {
    const auto gate = std::make_shared<GatedStage>();
    CollisionWorld cw(std::make_shared<Detector>(gate));
    CollisionObject oa = CollisionObject::deforming(ball, "a"), ob = CollisionObject::deforming(other, "b");
    cw.add(&oa);
    cw.add(&ob);
    const std::vector<std::pair<const char*, std::function<void()>>> entries = {
        {"add", [&] { cw.add(&oa); }},
        {"clear", [&] { cw.clear(); }},
        {"detect", [&] { (void)cw.detect(opt); }},
    };
    std::size_t pairs = 0;
    refused_while_inside(*gate, [&] { pairs = cw.detect(opt).pairs.size(); }, entries, "peelcd::CollisionWorld");
    CHECK(pairs == 1);
  }
}
