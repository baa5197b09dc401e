// Self-collision (docs/design.md, "Self-collision"): the definition (adjacent triangles are
// never pairs; by index or by position), the self search against the exact self reference, and
// every self class of peelcd/eval/classes.h with no miss on the exact path and on the
// conservative image stage at any tile; inter-object pairs unchanged beside self pairs.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/image/planner.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/world/world.h"
#include "peelcd/eval/classes.h"

#include <catch2/catch.hpp>
#include "fixtures.h"

#include <algorithm>
#include <random>

using namespace peelcd;

namespace {

using test::cpu_detector;

std::vector<std::uint64_t> self_pairs_found(const FrameResult& f, std::size_t object) {
  std::vector<std::uint64_t> out;
  for (const PairResult& p : f.pairs)
    if (p.object_a == object && p.object_b == object)
      for (const Contact& c : p.colliding) out.push_back(pack_pair(c.tri_a, c.tri_b));
  return out;
}

// Two triangles crossing each other, as one mesh, in two ways: with distinct vertices (a self
// pair), and with one corner shared (adjacent: never a pair).
Mesh two_crossing(bool share_corner) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -0.5}, {0.3, 0.2, 0.5}, {0.2, 0.4, 0.5}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  if (share_corner) m.triangles[1] = {0, 4, 5};
  return m;
}

}  // namespace

TEST_CASE("self pairs: triangles that share a point and no vertex", "[self]") {
  CHECK(exact_self_pairs(two_crossing(false)) == std::vector<std::uint64_t>{pack_pair(0, 1)});
  CHECK(exact_self_pairs(two_crossing(true)).empty());  // adjacent: excluded, crossing or not

  // Position adjacency: a duplicated corner (distinct index, same position) counts as shared.
  Mesh seam = two_crossing(false);
  seam.vertices[3] = seam.vertices[0];  // triangle 1 starts at triangle 0's first corner
  CHECK(exact_self_pairs(seam, SelfAdjacency::index) == std::vector<std::uint64_t>{pack_pair(0, 1)});
  CHECK(exact_self_pairs(seam, SelfAdjacency::position).empty());
  std::vector<std::uint32_t> rep;
  vertex_representatives(seam, SelfAdjacency::position, rep);
  CHECK(rep[3] == 0);
  CHECK(triangles_adjacent(seam, rep, 0, 1));
}

TEST_CASE("self on defective meshes: duplicate, zero-area and non-manifold triangles give defined results", "[self]") {
  Mesh m = floor_mesh(4, 0, 1, 0, 1, 0);  // 32 triangles, a flat open grid: no self pair
  const std::size_t flat = m.triangles.size();
  m.triangles.push_back(m.triangles[5]);  // a duplicate of triangle 5 (same indices): adjacent
  m.triangles.push_back({0, 0, 1});       // zero-area (repeated index): adjacent to its fan
  // A non-manifold edge: a third triangle on the edge (0, 1), standing up from the sheet.
  m.vertices.push_back(Vec3(0.1, 0.0, 0.5));
  m.triangles.push_back({0, 1, std::uint32_t(m.vertices.size() - 1)});
  // A duplicate with its own vertices (same positions): coplanar with the original, a pair by
  // index, none by position.
  const std::uint32_t base = std::uint32_t(m.vertices.size());
  for (int c = 0; c < 3; ++c) m.vertices.push_back(m.vertices[m.triangles[12][c]]);
  m.triangles.push_back({base, base + 1, base + 2});
  const auto by_index = exact_self_pairs(m, SelfAdjacency::index);
  const auto by_position = exact_self_pairs(m, SelfAdjacency::position);
  CHECK(std::binary_search(by_index.begin(), by_index.end(), pack_pair(12, std::uint32_t(m.triangles.size() - 1))));
  CHECK(by_position.empty());
  // The frame finds exactly the reference's pairs on both paths.
  std::vector<Object> objects(1);
  objects[0].name = "defects";
  objects[0].mesh = m;
  objects[0].self = true;
  for (const Stage stage : {Stage::exact, Stage::image})
    for (const SelfAdjacency adjacency : {SelfAdjacency::index, SelfAdjacency::position}) {
      DetectOptions opt;
      opt.stage = stage;
      opt.self_adjacency = adjacency;
      const FrameResult f = cpu_detector().detect(objects, opt);
      auto found = self_pairs_found(f, 0);
      std::sort(found.begin(), found.end());
      CHECK(found == (adjacency == SelfAdjacency::index ? by_index : by_position));
    }
  CHECK(flat == 32);
}

TEST_CASE("the self search finds every reference pair's candidate and tests no adjacent pair", "[self]") {
  for (const GeometryClass& g : self_classes()) {
    const Mesh& m = g.objects[0].mesh;
    std::vector<std::uint32_t> rep;
    vertex_representatives(m, SelfAdjacency::index, rep);
    std::vector<std::uint64_t> cands;
    SelfTree st;
    self_overlap_pairs(m, st, rep, cands);
    std::sort(cands.begin(), cands.end());
    for (const std::uint64_t c : cands) {
      REQUIRE(pair_a(c) < pair_b(c));
      REQUIRE_FALSE(triangles_adjacent(m, rep, pair_a(c), pair_b(c)));
    }
    const auto exact = exact_self_pairs(m);
    INFO(g.name);
    CHECK(std::includes(cands.begin(), cands.end(), exact.begin(), exact.end()));
  }
}

TEST_CASE("every self class: no self pair missed, exact path and conservative image stage at any tile", "[self][classes]") {
  for (const GeometryClass& g : self_classes()) {
    for (const Stage stage : {Stage::exact, Stage::image, Stage::automatic})
      for (const int res : {0, 16, 64}) {
        if (stage != Stage::image && res != 0) continue;
        DetectOptions opt;  // the default: conservative
        opt.stage = stage;
        opt.resolution = res;
        const ClassRow r = measure_class(cpu_detector(), g, "default", opt, 1);
        INFO(g.name << ", stage " << to_string(stage) << ", tile " << res << ": " << r.found << " of " << r.exact);
        CHECK(r.exact > 0);
        CHECK(r.missed == 0);
      }
  }
}

TEST_CASE("self pairs beside inter-object pairs: off changes nothing, on keeps every inter-object pair", "[self]") {
  std::vector<GeometryClass> classes = self_classes();
  GeometryClass& g = classes.back();  // a folded sheet on a ball
  REQUIRE(g.objects.size() == 2);
  DetectOptions opt;
  opt.stage = Stage::image;
  const FrameResult on = cpu_detector().detect(g.objects, opt);
  for (Object& o : g.objects) o.self = false;
  const FrameResult off = cpu_detector().detect(g.objects, opt);
  REQUIRE(off.pairs.size() == 1);  // the inter-object pair alone
  REQUIRE(on.pairs.size() == 2);   // (0, 0) first, then (0, 1)
  CHECK(on.pairs[0].object_a == 0);
  CHECK(on.pairs[0].object_b == 0);
  CHECK(!on.pairs[0].colliding.empty());
  const auto inter = [](const PairResult& p) {
    std::vector<std::uint64_t> v;
    for (const Contact& c : p.colliding) v.push_back(pack_pair(c.tri_a, c.tri_b));
    return v;
  };
  CHECK(inter(on.pairs[1]) == inter(off.pairs[0]));
  CHECK(inter(off.pairs[0]) == exact_colliding_pairs(g.objects[0].mesh, g.objects[1].mesh));
  // DetectOptions::self asks it for every object: the ball has no self pair, the cloth its own.
  opt.self = true;
  const FrameResult all = cpu_detector().detect(g.objects, opt);
  REQUIRE(all.pairs.size() == 3);
  CHECK(all.pairs[2].object_a == 1);
  CHECK(all.pairs[2].colliding.empty());
  CHECK(self_pairs_found(all, 0) == self_pairs_found(on, 0));
}

TEST_CASE("the World's self pairs: its tree against itself, equal to the frame's, rigid bodies cached", "[self][world]") {
  for (const GeometryClass& g : self_classes()) {
    DetectOptions opt;
    opt.stage = Stage::exact;
    const FrameResult frame = cpu_detector().detect(g.objects, opt);
    World world;
    std::vector<BodyId> ids;
    sync_bodies(world, g.objects, ids);
    const FrameResult& w = world.collide(opt);
    INFO(g.name);
    REQUIRE(w.pairs.size() == frame.pairs.size());
    for (std::size_t p = 0; p < w.pairs.size(); ++p) {
      CHECK(w.pairs[p].object_a == frame.pairs[p].object_a);
      CHECK(w.pairs[p].object_b == frame.pairs[p].object_b);
      REQUIRE(w.pairs[p].colliding.size() == frame.pairs[p].colliding.size());
      for (std::size_t c = 0; c < w.pairs[p].colliding.size(); ++c) {
        CHECK(w.pairs[p].colliding[c].tri_a == frame.pairs[p].colliding[c].tri_a);
        CHECK(w.pairs[p].colliding[c].tri_b == frame.pairs[p].colliding[c].tri_b);
      }
    }
  }
  // A rigid self body: its pairs found once on its shape, then moved by the pose.
  const GeometryClass knot = self_classes()[1];
  auto shape = std::make_shared<const Mesh>(knot.objects[0].mesh);
  World world;
  const BodyId id = world.add_rigid(shape, Eigen::Affine3d::Identity(), "knot");
  world.set_self(id, true);
  DetectOptions opt;
  const std::vector<std::uint64_t> exact = exact_self_pairs(*shape);
  const FrameResult first = world.collide(opt);
  REQUIRE(first.pairs.size() == 1);
  CHECK(first.pairs[0].candidates > 0);
  CHECK(first.pairs[0].colliding.size() == exact.size());
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  pose.translate(Vec3(3, -2, 1));
  pose.rotate(Eigen::AngleAxisd(0.7, Vec3(0, 1, 1).normalized()));
  world.set_pose(id, pose);
  const FrameResult moved = world.collide(opt);
  REQUIRE(moved.pairs.size() == 1);
  CHECK(moved.pairs[0].candidates == 0);  // nothing tested again: the shape's pairs, cached
  REQUIRE(moved.pairs[0].colliding.size() == exact.size());
  for (std::size_t c = 0; c < exact.size(); ++c) {
    CHECK(pack_pair(moved.pairs[0].colliding[c].tri_a, moved.pairs[0].colliding[c].tri_b) == exact[c]);
    CHECK((moved.pairs[0].colliding[c].p - pose * first.pairs[0].colliding[c].p).norm() < 1e-12);
  }
  world.set_self(id, false);
  CHECK(world.collide(opt).pairs.empty());
}

// The crumpled cloth of `peelcd bench cloth-crumpled`: it does pass through itself, and the World
// finds exactly the reference's self pairs frame after frame (its tree refitted, the refit
// split over two threads or not).
TEST_CASE("the crumpled cloth: self pairs exist and the World finds exactly them, one or two threads", "[self]") {
  for (const unsigned threads : {1u, 2u}) {
    World world;
    const BodyId cloth = world.add_deforming(make_crumpled_cloth(60, 0.0), "cloth");
    world.set_self(cloth, true);
    DetectOptions opt;
    opt.threads = threads;
    for (int f = 0; f < 3; ++f) {
      const Mesh m = make_crumpled_cloth(60, 0.15 * f);
      world.set_vertices(cloth, m.vertices);
      const FrameResult& r = world.collide(opt);
      const std::vector<std::uint64_t> want = exact_self_pairs(m);
      INFO("threads " << threads << ", frame " << f);
      REQUIRE(want.size() > 100);
      REQUIRE(r.pairs.size() == 1);
      std::vector<std::uint64_t> got;
      for (const Contact& c : r.pairs[0].colliding) got.push_back(pack_pair(c.tri_a, c.tri_b));
      std::sort(got.begin(), got.end());
      CHECK(got == want);
      // Not routed, but predicted by the World's model from the couples tested.
      CHECK(r.pairs[0].candidates > want.size());
      CHECK(r.pairs[0].predicted_exact_ms > 0.0);
      CHECK(r.pairs[0].predicted_exact_ms == Approx(world_exact_cost().predict_ms(double(r.pairs[0].candidates), 0.0)));
    }
  }
}

TEST_CASE("a large cloth's self traversal split over the lanes: the same contacts and couples on 1, 2 and 3 threads", "[self][world]") {
  // Over kSplitTriangles: on several lanes the World's self traversal is split into node pairs
  // (bvh_self_split) and its rebuilt tree built in subtrees (Bvh::plan_build), and so is the
  // frame API's traversal (kSpreadSelfTriangles); each couple is still tested once, every contact
  // found, kinds and segments as on one lane, in both APIs.
  const Mesh first = make_crumpled_cloth(130, 0.0);
  REQUIRE(first.triangles.size() >= 32768);
  std::vector<std::vector<Contact>> got;
  std::vector<std::size_t> tested;
  for (const unsigned threads : {1u, 2u, 3u}) {  // the frame API
    Detector d(std::make_shared<CpuImageStage>());
    std::vector<Object> objects(1);
    objects[0].name = "cloth";
    objects[0].self = true;
    objects[0].mesh = first;
    DetectOptions opt;
    opt.stage = Stage::exact;
    opt.threads = threads;
    std::vector<Contact> all;
    std::size_t candidates = 0;
    for (int f = 0; f < 3; ++f) {
      objects[0].mesh.vertices = make_crumpled_cloth(130, 0.3 * f).vertices;
      const FrameResult r = d.detect(objects, opt);
      REQUIRE(r.pairs.size() == 1);
      all.insert(all.end(), r.pairs[0].colliding.begin(), r.pairs[0].colliding.end());
      candidates += r.pairs[0].candidates;
    }
    got.push_back(all);
    tested.push_back(candidates);
  }
  for (const unsigned threads : {1u, 2u, 3u}) {  // the World
    World world;
    const BodyId cloth = world.add_deforming(first, "cloth");
    world.set_self(cloth, true);
    DetectOptions opt;
    opt.threads = threads;
    std::vector<Contact> all;
    std::size_t candidates = 0;
    for (int f = 0; f < 3; ++f) {
      const Mesh m = make_crumpled_cloth(130, 0.3 * f);
      world.set_vertices(cloth, m.vertices);
      const FrameResult& r = world.collide(opt);
      REQUIRE(r.pairs.size() == 1);
      if (f == 2) {
        const std::vector<std::uint64_t> want = exact_self_pairs(m);
        std::vector<std::uint64_t> keys;
        for (const Contact& c : r.pairs[0].colliding) keys.push_back(pack_pair(c.tri_a, c.tri_b));
        std::sort(keys.begin(), keys.end());
        INFO("threads " << threads);
        CHECK(keys == want);
      }
      all.insert(all.end(), r.pairs[0].colliding.begin(), r.pairs[0].colliding.end());
      candidates += r.pairs[0].candidates;
    }
    got.push_back(all);
    tested.push_back(candidates);
  }
  REQUIRE(got[0].size() > 1000);
  for (std::size_t k = 1; k < got.size(); ++k) {
    INFO("run " << k << " (0-2: the frame API on 1, 2, 3 threads; 3-5: the World)");
    CHECK(tested[k] == tested[0]);  // no couple tested twice or left out
    REQUIRE(got[k].size() == got[0].size());
    bool same = true;
    for (std::size_t i = 0; i < got[0].size(); ++i) {
      const Contact &a = got[k][i], &b = got[0][i];
      same = same && a.tri_a == b.tri_a && a.tri_b == b.tri_b && a.kind == b.kind && a.p == b.p && a.q == b.q;
    }
    CHECK(same);
  }
}

TEST_CASE("a kept self tree: refitted while the triangles stay, the same candidates as a tree built each frame", "[self]") {
  SelfTree st;
  // The kept tree's candidates of `m` (sorted), checked equal to those of a tree built for it.
  const auto kept_pairs = [&st](const Mesh& m) {
    std::vector<std::uint32_t> rep;
    vertex_representatives(m, SelfAdjacency::index, rep);
    std::vector<std::uint64_t> kept, fresh;
    SelfTree built;  // a tree built for m
    self_overlap_pairs(m, st, rep, kept);
    self_overlap_pairs(m, built, rep, fresh);
    std::sort(kept.begin(), kept.end());
    std::sort(fresh.begin(), fresh.end());
    CHECK(kept == fresh);
    return kept;
  };
  for (int f = 0; f < 4; ++f) {
    INFO("frame " << f);
    CHECK_FALSE(kept_pairs(make_crumpled_cloth(24, 0.3 + 0.05 * f)).empty());  // 1,152 triangles folding further
    CHECK(st.builds == 1);  // built on the first frame only
  }
  // New triangles: built again.
  Mesh cut = make_crumpled_cloth(24, 0.5);
  cut.triangles.pop_back();
  kept_pairs(cut);
  CHECK(st.builds == 2);
  // Vertices shuffled under the same triangles: the refitted tree's grouping no longer fits
  // them, its boxes grow far past kBvhRebuildGrowth, and it is built again in the same frame.
  Mesh shuffled = cut;
  std::mt19937 rng(7);
  std::shuffle(shuffled.vertices.begin(), shuffled.vertices.end(), rng);
  kept_pairs(shuffled);
  CHECK(st.builds == 3);
  CHECK(st.tree.growth() == 1.0);
  kept_pairs(shuffled);  // the same vertices again: refitted, no growth
  CHECK(st.builds == 3);
}

TEST_CASE("the frame API over a cloth folding frame by frame: exactly the exact self pairs every frame", "[self]") {
  Detector d(std::make_shared<CpuImageStage>());
  std::vector<Object> objects(1);
  objects[0].name = "cloth";
  objects[0].self = true;
  DetectOptions opt;
  opt.stage = Stage::exact;
  for (int f = 0; f < 3; ++f) {
    objects[0].mesh = make_crumpled_cloth(24, 0.3 + 0.1 * f);
    const FrameResult r = d.detect(objects, opt);
    const auto want = exact_self_pairs(objects[0].mesh);
    INFO("frame " << f);
    CHECK_FALSE(want.empty());
    CHECK(self_pairs_found(r, 0) == want);  // sorted as every path gives them
  }
  // Under Stage::automatic: the exact path, predicted by its candidate couples (the World's
  // model), not by its triangles.
  opt.stage = Stage::automatic;
  const FrameResult r = d.detect(objects, opt);
  REQUIRE(r.pairs.size() == 1);
  CHECK(r.pairs[0].exact_stage);
  CHECK(r.pairs[0].candidates > objects[0].mesh.triangles.size());
  CHECK(r.pairs[0].predicted_exact_ms == Approx(1e-3 * kWorldCandidateUs * double(r.pairs[0].candidates)));
  CHECK_THAT(pair_path_reason(r.pairs[0], opt), Catch::Contains("a self pair"));
}
