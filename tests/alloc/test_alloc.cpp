// Steady state allocates nothing: the frame loop of a simulation (the same objects moving,
// Pipeline::detect into a reused FrameResult) makes no C++ heap allocation once its buffers
// have grown to the working set. The motion here is periodic: the first period warms up, the
// second must not allocate. (A new maximum of PCS or contacts grows a buffer once, geometrically.)
// Counted: every operator new in this process (replaced below). Not counted: the GL driver's
// own malloc calls inside GL functions, which peelcd does not control.
#include "peelcd/core/primitives.h"
#include "peelcd/core/world/world.h"
#include "peelcd/gl/pipeline.h"
#include "peelcd/gl_osmesa/osmesa_context.h"

#include <catch2/catch.hpp>

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<std::size_t> g_allocations{0};
}

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  ++g_allocations;
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

using namespace peelcd;

TEST_CASE("a steady stream of frames allocates nothing", "[alloc]") {
  gl::Pipeline pipeline(std::make_shared<gl::OsmesaContext>());
  // Two spheres and a rigid ball moving a little every frame: two ROIs, contacts every frame.
  const Mesh big = make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32);
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 0.6, 12, 24));
  std::vector<Object> objects(3);
  objects[0] = {"big", big, {}, {}};
  objects[1] = {"small", make_uv_sphere(Vec3(0.9, 0.3, 0.1), 0.5, 12, 24), {}, {}};
  objects[2] = {"ball", *ball, RigidMotion{ball, Eigen::Affine3d::Identity()}, {}};
  const Mesh small = objects[1].mesh;
  const auto move = [&](int f) {
    const int phase = f % 5;  // period 5
    const Vec3 at(-0.9 + 0.03 * phase, -0.4, 0.2);
    objects[2].rigid->pose = Eigen::Translation3d(at);
    for (std::size_t i = 0; i < ball->vertices.size(); ++i) objects[2].mesh.vertices[i] = ball->vertices[i] + at;
    for (std::size_t i = 0; i < small.vertices.size(); ++i)  // a deforming object: new vertices
      objects[1].mesh.vertices[i] = small.vertices[i] * (1.0 + 0.02 * phase);
  };
  // Both peelers through the image stage, and the exact CPU path (Stage::exact).
  for (const auto& [peeler, stage] : {std::pair{Peeler::abuffer, Stage::image}, std::pair{Peeler::multipass, Stage::image},
                                      std::pair{Peeler::abuffer, Stage::exact}}) {
    pipeline.set_gl_options({peeler});
    DetectOptions opt;
    opt.stage = stage;
    opt.resolution = 128;
    FrameResult result;
    for (int f = 0; f < 5; ++f) {  // warm-up: one period; buffers grow to their working size
      move(f);
      pipeline.detect(objects, opt, result);
    }
    std::size_t before = 0, after = 0, contacts = 0;
    for (int f = 5; f < 10; ++f) {
      move(f);
      before = g_allocations.load();
      pipeline.detect(objects, opt, result);
      after = g_allocations.load();
      INFO("peeler " << to_string(peeler) << ", stage " << to_string(stage) << ", frame " << f);
      CHECK(after - before == 0);
      REQUIRE(result.pairs.size() == 2);
      contacts += result.pairs[0].colliding.size() + result.pairs[1].colliding.size();
    }
    CHECK(contacts > 0);
  }
}

TEST_CASE("a World's steady frames allocate nothing: poses and vertices set, contacts found", "[alloc][world]") {
  // Named bodies (names past the small-string buffer: a label built per call would allocate),
  // a rigid ball posed every frame, a deforming sphere given new vertices, a static sphere.
  World world;
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 0.6, 12, 24));
  const Mesh small = make_uv_sphere(Vec3(0.9, 0.3, 0.1), 0.5, 12, 24);
  const BodyId big = world.add_rigid(std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32)),
                                     Eigen::Affine3d::Identity(), "the big static sphere in the middle");
  const BodyId moving = world.add_rigid(ball, Eigen::Affine3d::Identity(), "a rigid ball that moves every frame");
  const BodyId soft = world.add_deforming(small, "a deforming sphere that breathes");
  std::vector<Vec3> vertices = small.vertices;
  const auto move = [&](int f) {
    const int phase = f % 5;  // period 5
    world.set_pose(moving, Eigen::Affine3d(Eigen::Translation3d(-0.9 + 0.03 * phase, -0.4, 0.2)));
    for (std::size_t i = 0; i < small.vertices.size(); ++i) vertices[i] = small.vertices[i] * (1.0 + 0.02 * phase);
    world.set_vertices(soft, vertices);
    world.set_pose(big, Eigen::Affine3d::Identity());
  };
  for (const ContactDetail detail : {ContactDetail::segments, ContactDetail::pairs}) {
    DetectOptions opt;
    opt.contacts = detail;
    FrameResult result;
    for (int f = 0; f < 5; ++f) {  // warm-up: one period
      move(f);
      world.collide(opt, result);
    }
    std::size_t contacts = 0;
    for (int f = 5; f < 10; ++f) {
      const std::size_t before = g_allocations.load();
      move(f);
      world.collide(opt, result);
      const std::size_t after = g_allocations.load();
      INFO("contacts " << to_string(detail) << ", frame " << f);
      CHECK(after - before == 0);
      for (const PairResult& p : result.pairs) contacts += p.colliding.size();
    }
    CHECK(contacts > 0);
  }
}

TEST_CASE("a World's steady frames planned for 3 lanes allocate nothing, large bodies split for the lanes", "[alloc][world]") {
  // A pair over kSplitTriangles: its traversal split into node pairs for the lanes every frame
  // (bvh_split), a large deforming body's refit in chunks and subtrees, its vertices loaded in
  // parts. Planned for 3 lanes by the lane model (World::model_lanes) and run on this thread:
  // with real lanes, which lane takes which item varies from frame to frame (a lane done early
  // takes the others' items), so a lane's scratch may first grow in any frame; the plan, its
  // splits and its tasks are the same either way.
  World world;
  world.model_lanes(3);
  auto shape = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 1.0, 64, 96));
  const Mesh large = make_uv_sphere(Vec3(0, 0, 0), 1.0, 130, 132);
  const BodyId rigid = world.add_rigid(shape, Eigen::Affine3d::Identity());
  const BodyId soft = world.add_deforming(large);
  std::vector<Vec3> vertices = large.vertices;
  const auto move = [&](int f) {
    const int phase = f % 4;  // period 4
    // (turned and off the axes: crossings in general position, no exact construction of a
    // degenerate contact, whose arbitrary-precision numbers allocate)
    world.set_pose(rigid, Eigen::Translation3d(1.1 + 0.0213 * phase, 0.317, 0.0291) *
                              Eigen::AngleAxisd(0.37 + 0.01 * phase, Eigen::Vector3d(0.3, 0.8, 0.5).normalized()));
    for (std::size_t i = 0; i < large.vertices.size(); ++i) vertices[i] = large.vertices[i] * (1.0 + 0.01 * phase);
    world.set_vertices(soft, vertices);
  };
  DetectOptions opt;
  opt.threads = 1;
  opt.stage = Stage::exact;
  FrameResult result;
  for (int f = 0; f < 8; ++f) {  // warm-up: two periods (the rebuild rule may build the tree once)
    move(f);
    world.collide(opt, result);
  }
  std::size_t contacts = 0;
  for (int f = 8; f < 12; ++f) {
    const std::size_t before = g_allocations.load();
    move(f);
    world.collide(opt, result);
    const std::size_t after = g_allocations.load();
    INFO("frame " << f);
    CHECK(after - before == 0);
    for (const PairResult& p : result.pairs) contacts += p.colliding.size();
  }
  CHECK(contacts > 0);
}
