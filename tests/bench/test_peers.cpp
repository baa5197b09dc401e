// The benchmark's peers (peelcd/bench/peers.h) answer the same question as the exact reference:
// CGAL cropped to the overlap box, and FCL in both modes, on every class of geometry and on
// frames of the crowd (rigid, deforming and mixed pairs). FCL keeps a rigid shape's tree: its
// builds do not grow with the frames. (FCL's triangle test is not exact: its contacts are
// checked on scenes far from the degenerate cases where double rounding decides.)
#include "peelcd/bench/float_peers.h"
#include "peelcd/bench/peers.h"
#include "peelcd/bench/plain_peers.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/eval/classes.h"
#include "peelcd/eval/scenes.h"

#include <catch2/catch.hpp>

#include <map>

using namespace peelcd;

namespace {
// The exact pairs of every object pair whose boxes overlap, in broad-phase order.
bench::PeerFrame exact(const std::vector<Object>& objects) {
  bench::PeerFrame f;
  std::vector<Aabb> boxes;
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  f.objects = overlapping_pairs(boxes);
  for (const auto& [a, b] : f.objects) f.per_pair.push_back(exact_colliding_pairs(objects[a].mesh, objects[b].mesh));
  return f;
}

// The peer's pairs with contacts equal the exact ones with contacts.
void require_same(const bench::PeerFrame& want, const bench::PeerFrame& got) {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>> w, g;
  for (std::size_t i = 0; i < want.objects.size(); ++i)
    if (!want.per_pair[i].empty()) w[want.objects[i]] = want.per_pair[i];
  for (std::size_t i = 0; i < got.objects.size(); ++i)
    if (!got.per_pair[i].empty()) g[got.objects[i]] = got.per_pair[i];
  CHECK(w == g);
}
}  // namespace

TEST_CASE("the CGAL peer, cropped, finds the exact pairs on every class", "[peers]") {
  for (const GeometryClass& g : geometry_classes(5)) {
    INFO(g.name);
    for (unsigned threads : {1u, 2u}) require_same(exact(g.objects), bench::cgal_frame(g.objects, threads));
  }
}

TEST_CASE("the FCL peer finds the exact pairs on the crowd, rigid, deforming and mixed", "[peers]") {
  const auto crowd = make_crowd(30, 4);
  for (const auto mode : {bench::FclPeer::Deforming::refit, bench::FclPeer::Deforming::rebuild}) {
    bench::FclPeer fcl(mode, 2);
    std::vector<Object> objects;
    std::size_t builds_after_first = 0;  // rigid shape, deforming balls (rebuild: per pair)
    for (std::size_t f = 0; f < crowd->frames(); ++f) {
      crowd->frame(f, objects);
      INFO("mode " << int(mode) << ", frame " << f);
      const bench::PeerFrame want = exact(objects);
      std::size_t contacts = 0;
      for (const auto& p : want.per_pair) contacts += p.size();
      REQUIRE(contacts > 0);
      require_same(want, fcl.frame(objects));
      require_same(want, bench::cgal_frame(objects, 2));
      if (f == 0) builds_after_first = fcl.builds();
    }
    // Refit mode: 24 of the 30 balls are rigid and share one shape (one tree), the 6 breathing
    // ones are built in the first frame and refitted after it.
    // Rebuild mode: only the shared tree is kept; the breathing balls' trees are cropped per pair.
    CHECK(fcl.builds() == builds_after_first);
    if (mode == bench::FclPeer::Deforming::refit) {
      CHECK(builds_after_first == 7);
      CHECK(fcl.refits() == 6 * (crowd->frames() - 1));
    } else {
      CHECK(builds_after_first == 1);
      CHECK(fcl.refits() == 0);
      CHECK(fcl.pair_builds() > 0);
    }
  }
}

TEST_CASE("FCL keeps a rigid shape's tree across frames", "[peers]") {
  auto shape = std::make_shared<const Mesh>(uv_sphere(Vec3::Zero(), 1.0, 16, 8));
  bench::FclPeer fcl(bench::FclPeer::Deforming::rebuild, 1);
  std::vector<Object> objects(2);
  for (int f = 0; f < 5; ++f) {
    for (int i = 0; i < 2; ++i) {
      const Eigen::Affine3d pose = Eigen::Translation3d(Vec3(1.5 * i + 0.01 * f + 0.1, 0.1 * i, 0)) *
                                   Eigen::AngleAxisd(0.3 * f + i, Vec3(0, 0, 1));
      objects[std::size_t(i)].mesh = transformed(*shape, Transform{});
      for (Vec3& v : objects[std::size_t(i)].mesh.vertices) v = pose * v;
      objects[std::size_t(i)].rigid = RigidMotion{shape, pose};
    }
    require_same(exact(objects), fcl.frame(objects));
  }
  CHECK(fcl.builds() == 1);  // one shape, one tree shared by both objects, five frames
  CHECK(fcl.refits() == 0);
  CHECK(fcl.pair_builds() == 0);
}

// Embree's and Bullet's float test agrees with the exact one away from rounding: the crowd
// (rigid, deforming and mixed pairs over frames), two rigid spheres (A's frame kept, B mapped)
// and a self pair (a folded sheet), with threads.
TEST_CASE("the Embree and Bullet peers find the exact pairs on the crowd, a rigid pair and a self pair", "[peers]") {
  const auto crowd = make_crowd(30, 4);
  // The scaled float test (tri_tri_float()): exact away from rounding on these scenes, so the
  // peers' trees, updates and pair lists are what is checked here; the published test's own
  // misses and false pairs are the bench's to count.
  const auto sc = bench::TriangleTest::scaled;
  bench::EmbreePeer embree_refit(bench::EmbreePeer::Update::refit, 2, sc), embree_low(bench::EmbreePeer::Update::rebuild_low, 1, sc);
  bench::BulletPeer bullet(2, sc);
  std::vector<Object> objects;
  for (std::size_t f = 0; f < crowd->frames(); ++f) {
    crowd->frame(f, objects);
    INFO("crowd frame " << f);
    const bench::PeerFrame want = exact(objects);
    require_same(want, embree_refit.frame(objects));
    require_same(want, embree_low.frame(objects));
    require_same(want, bullet.frame(objects));
  }
  CHECK(bullet.builds() == 7);  // one shared rigid shape, 6 breathing balls built once, then refitted
  CHECK(bullet.refits() == 6 * (crowd->frames() - 1));

  auto shape = std::make_shared<const Mesh>(uv_sphere(Vec3::Zero(), 1.0, 16, 8));
  bench::EmbreePeer e2(bench::EmbreePeer::Update::refit, 1, sc);
  bench::BulletPeer b2(1, sc);
  std::vector<Object> pair(2);
  for (int f = 0; f < 4; ++f) {
    for (int i = 0; i < 2; ++i) {
      const Eigen::Affine3d pose = Eigen::Translation3d(Vec3(1.5 * i + 0.01 * f + 0.1, 0.1 * i, 0)) *
                                   Eigen::AngleAxisd(0.3 * f + i, Vec3(0, 0, 1));
      pair[std::size_t(i)].mesh = transformed(*shape, Transform{});
      for (Vec3& v : pair[std::size_t(i)].mesh.vertices) v = pose * v;
      pair[std::size_t(i)].rigid = RigidMotion{shape, pose};
    }
    INFO("rigid pair frame " << f);
    const bench::PeerFrame want = exact(pair);
    REQUIRE_FALSE(want.per_pair.empty());
    require_same(want, e2.frame(pair));
    require_same(want, b2.frame(pair));
  }
  CHECK(e2.builds() == 2);  // A in its frame (a static scene), B once (dynamic); then B refitted as it moves
  CHECK(b2.builds() == 1);  // one shape for both

  // A self pair: one object made of two crossing spheres (a folded sheet's coplanar neighbours
  // are where float rounding decides, so not here).
  std::vector<Object> sheet(1);
  sheet[0].mesh = uv_sphere(Vec3::Zero(), 1.0, 16, 8);
  const Mesh other = uv_sphere(Vec3(1.2, 0.3, 0.1), 0.8, 16, 8);
  const auto base = std::uint32_t(sheet[0].mesh.vertices.size());
  sheet[0].mesh.vertices.insert(sheet[0].mesh.vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const Tri& t : other.triangles) sheet[0].mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  sheet[0].self = true;
  bench::PeerFrame want;
  want.objects = {{0, 0}};
  want.per_pair = {exact_self_pairs(sheet[0].mesh)};
  REQUIRE_FALSE(want.per_pair[0].empty());
  require_same(want, bench::EmbreePeer(bench::EmbreePeer::Update::refit, 1, sc).frame(sheet));
  require_same(want, bench::BulletPeer(1, sc).frame(sheet));
  // The plain Embree setup of --audit: the scene against itself, each couple once, neighbours
  // (a shared vertex index) left out, Moller's test: the Embree row's pairs with the same test.
  bench::PlainPeer plain(bench::PlainPeer::Library::embree);
  const bench::PeerFrame self_plain = plain.frame(sheet);
  REQUIRE(self_plain.objects == want.objects);
  require_same(bench::EmbreePeer(bench::EmbreePeer::Update::refit, 1).frame(sheet), self_plain);
  CHECK(self_plain.pairs > 0);
}

TEST_CASE("the plain Embree setup of --audit finds the Embree peer's pairs, refits what moves, keeps what does not", "[peers]") {
  // Both run Moller's published test on the same float corners (world space: the crowd has no
  // rigid pair), so their pairs are the same, misses and false pairs included.
  const auto crowd = make_crowd(30, 4);
  bench::EmbreePeer embree(bench::EmbreePeer::Update::refit, 1);
  bench::PlainPeer plain(bench::PlainPeer::Library::embree);
  std::vector<Object> objects;
  for (std::size_t f = 0; f < crowd->frames(); ++f) {
    crowd->frame(f, objects);
    INFO("crowd frame " << f);
    const bench::PeerFrame want = embree.frame(objects), got = plain.frame(objects);
    CHECK(got.pairs > 0);
    require_same(want, got);
  }
  // Each object built once, and again as dynamic when it first moves (the breathing balls too:
  // the plain setup does not know which objects deform); refitted after that.
  CHECK(plain.builds() <= 2 * objects.size());
  CHECK(plain.builds() + plain.refits() == embree.builds() + embree.refits());  // a commit for every change
  CHECK(plain.variant());  // never the best peer
  CHECK(plain.setup().find("low quality") != std::string::npos);
}

TEST_CASE("Moller's published test: crossing, above, coplanar overlapping and apart, a micrometre gap", "[peers]") {
  const std::array<float, 9> t = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  CHECK(bench::tri_tri_moller(t, {0.2f, 0.2f, -1, 0.2f, 0.2f, 1, 0.9f, 0.9f, 1}));   // pierces
  CHECK_FALSE(bench::tri_tri_moller(t, {0.2f, 0.2f, 0.1f, 0.3f, 0.2f, 1, 0.2f, 0.3f, 1}));  // above
  CHECK(bench::tri_tri_moller(t, {0.5f, 0.5f, 0, 2, 2, 0, 0.5f, 2, 0}));  // coplanar, overlapping
  CHECK_FALSE(bench::tri_tri_moller(t, {2, 2, 0, 3, 2, 0, 2, 3, 0}));     // coplanar, apart
  // A millimetre triangle half a micrometre above another: apart (no epsilon snaps it onto the
  // other's plane), as the scaled variant says too.
  const std::array<float, 9> small = {0, 0, 0, 1e-3f, 0, 0, 0, 1e-3f, 0};
  const std::array<float, 9> above = {1e-4f, 1e-4f, 5e-7f, 9e-4f, 1e-4f, 5e-7f, 1e-4f, 9e-4f, 5e-7f};
  CHECK_FALSE(bench::tri_tri_moller(small, above));
  CHECK_FALSE(bench::tri_tri_float(small, above));
}

TEST_CASE("each float peer says its setup", "[peers]") {
  const std::string refit = bench::EmbreePeer(bench::EmbreePeer::Update::refit).setup();
  CHECK_THAT(refit, Catch::Contains("static scene") && Catch::Contains("REFIT") && Catch::Contains("test moller"));
  CHECK_THAT(bench::EmbreePeer(bench::EmbreePeer::Update::rebuild_low, 1, bench::TriangleTest::scaled).setup(),
             Catch::Contains("Morton") && Catch::Contains("test scaled"));
  CHECK_THAT(bench::BulletPeer().setup(), Catch::Contains("btGImpactMeshShape") && Catch::Contains("test moller"));
}

TEST_CASE("the float triangle test: crossing, touching at a vertex, coplanar overlapping, disjoint", "[peers]") {
  const std::array<float, 9> t = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  CHECK(bench::tri_tri_float(t, {0.2f, 0.2f, -1, 0.2f, 0.2f, 1, 0.9f, 0.9f, 1}));   // pierces
  CHECK_FALSE(bench::tri_tri_float(t, {0.2f, 0.2f, 0.1f, 0.3f, 0.2f, 1, 0.2f, 0.3f, 1}));  // above
  CHECK(bench::tri_tri_float(t, {0.5f, 0.5f, 0, 2, 2, 0, 0.5f, 2, 0}));  // coplanar, overlapping
  CHECK_FALSE(bench::tri_tri_float(t, {2, 2, 0, 3, 2, 0, 2, 3, 0}));     // coplanar, apart
}

// A deforming object that travels: Bullet's quantized box set is refitted while its vertices stay
// within the range fixed at its build, built again when they leave it; every frame exact.
TEST_CASE("the Bullet peer follows a deforming object beyond its first bounds", "[peers]") {
  bench::BulletPeer bullet(1, bench::TriangleTest::scaled);
  bench::EmbreePeer embree(bench::EmbreePeer::Update::refit, 1, bench::TriangleTest::scaled);
  std::vector<Object> objects(2);
  objects[0].mesh = uv_sphere(Vec3::Zero(), 1.0, 24, 12);
  for (int f = 0; f < 10; ++f) {
    objects[1].mesh = uv_sphere(Vec3(-3.0 + 0.6 * f, 0.2, 0.1), 0.7, 24, 12);
    INFO("frame " << f);
    const bench::PeerFrame want = exact(objects);
    require_same(want, bullet.frame(objects));
    require_same(want, embree.frame(objects));
  }
  CHECK(bullet.builds() > 2);   // built again once it left the first range
  CHECK(bullet.refits() > 0);   // refitted while inside it
}

// Every exact pair of `want` is among `got`'s (a peer with its own float test may add near pairs);
// returns how many `got` adds.
std::size_t require_covers(const bench::PeerFrame& want, const bench::PeerFrame& got) {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>> g;
  for (std::size_t i = 0; i < got.objects.size(); ++i) g[got.objects[i]] = got.per_pair[i];
  std::size_t missed = 0, wanted = 0;
  for (std::size_t i = 0; i < want.objects.size(); ++i)
    for (std::uint64_t k : want.per_pair[i]) {
      const auto& have = g[want.objects[i]];
      missed += !std::binary_search(have.begin(), have.end(), k);
      ++wanted;
    }
  CHECK(missed == 0);
  CHECK(got.pairs + missed >= wanted);
  return got.pairs + missed - wanted;
}

// A plain setup on the crowd's frames (rigid balls placed by their transforms, deforming ones):
// every exact pair found in each.
void covers_on_crowd(bench::PlainPeer::Library library) {
  const auto crowd = make_crowd(30, 4);
  bench::PlainPeer plain(library);
  std::vector<Object> balls;
  for (std::size_t f = 0; f < crowd->frames(); ++f) {
    crowd->frame(f, balls);
    INFO("crowd frame " << f);
    const bench::PeerFrame got = plain.frame(balls);
    CHECK(got.pairs > 0);
    require_covers(exact(balls), got);
  }
}

// Bullet as a plain user sets it up (GImpact's own algorithm and triangle test in a collision
// world, pairs from the contact-added callback): every exact pair of a deforming sphere
// travelling through another, made again once it leaves its box set's quantization range (a
// refit clamps to it: without the new shape it finds nothing after the first frames), refitted
// within it; and of the crowd's frames (rigid balls placed by their transforms, one shape each).
TEST_CASE("the plain Bullet setup of --audit finds every exact pair, refits within its range, is made again beyond it", "[peers]") {
  bench::PlainPeer plain(bench::PlainPeer::Library::bullet);
  std::vector<Object> objects(2);
  objects[0].mesh = uv_sphere(Vec3::Zero(), 1.0, 24, 12);
  std::size_t hits = 0;
  for (int f = 0; f < 10; ++f) {
    objects[1].mesh = uv_sphere(Vec3(-3.0 + 0.6 * f, 0.2, 0.1), 0.7, 24, 12);
    INFO("frame " << f);
    const bench::PeerFrame want = exact(objects), got = plain.frame(objects);
    require_covers(want, got);
    hits += got.pairs;
  }
  CHECK(hits > 0);
  CHECK(plain.builds() > 2);  // made again once it left the first range
  CHECK(plain.refits() > 0);  // refitted while inside it
  CHECK(plain.variant());     // never the best peer
  CHECK_THAT(plain.setup(), Catch::Contains("gContactAddedCallback") && Catch::Contains("GImpact's own"));

  covers_on_crowd(bench::PlainPeer::Library::bullet);
}

// FCL as a plain user sets it up (OBBRSS models, the dynamic AABB tree manager, fcl::collide asking
// for every contact): every exact pair of a deforming sphere travelling through another (its model
// updated through FCL's update API, not built again), and of the crowd's frames (rigid balls
// placed by their transforms, one model per shape).
TEST_CASE("the plain FCL setup of --audit finds every exact pair, updates a deforming model in place", "[peers]") {
  bench::PlainPeer plain(bench::PlainPeer::Library::fcl);
  std::vector<Object> objects(2);
  objects[0].mesh = uv_sphere(Vec3::Zero(), 1.0, 24, 12);
  std::size_t hits = 0;
  for (int f = 0; f < 10; ++f) {
    objects[1].mesh = uv_sphere(Vec3(-3.0 + 0.6 * f, 0.2, 0.1), 0.7, 24, 12);
    INFO("frame " << f);
    const bench::PeerFrame want = exact(objects), got = plain.frame(objects);
    CHECK(require_covers(want, got) == 0);  // FCL's test adds no pair here
    hits += got.pairs;
  }
  CHECK(hits > 0);
  CHECK(plain.builds() == 2);  // each built once
  CHECK(plain.refits() == 9);  // the moving one updated every later frame; the still one never
  CHECK(plain.variant());
  CHECK_THAT(plain.setup(), Catch::Contains("OBBRSS") && Catch::Contains("updateSubModel"));

  covers_on_crowd(bench::PlainPeer::Library::fcl);
}
