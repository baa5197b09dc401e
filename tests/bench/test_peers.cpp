// The benchmark's peers (peelcd/bench/peers.h) answer the same question as the exact reference:
// CGAL cropped to the overlap box, and FCL in both modes, on every class of geometry and on
// frames of the crowd (rigid, deforming and mixed pairs). FCL keeps a rigid shape's tree: its
// builds do not grow with the frames. (FCL's triangle test is not exact: its contacts are
// checked on scenes far from the degenerate cases where double rounding decides.)
#include "peelcd/bench/peers.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/core/reference.h"
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
