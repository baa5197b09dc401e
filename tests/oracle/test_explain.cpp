// peelcd explain's verdicts on small constructed scenes, through the CPU image stage (no GL):
// each scene is built so that one verdict, and only it, is the right answer.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/io/error.h"
#include "peelcd/oracle/explain.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <cstdlib>
#include <fstream>

using namespace peelcd;
using namespace peelcd::oracle;
namespace fs = std::filesystem;

namespace {

struct Builder {
  Object o;
  explicit Builder(std::string name) { o.name = std::move(name); }
  std::uint32_t tri(const Vec3& a, const Vec3& b, const Vec3& c) {
    const auto base = std::uint32_t(o.mesh.vertices.size());
    o.mesh.vertices.insert(o.mesh.vertices.end(), {a, b, c});
    o.mesh.triangles.push_back({base, base + 1, base + 2});
    return std::uint32_t(o.mesh.triangles.size() - 1);
  }
  // Two triangles; returns the first's index.
  std::uint32_t quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    const std::uint32_t t = tri(a, b, c);
    tri(a, c, d);
    return t;
  }
};

// The paper's frame (view 0 along world x), point sampling, every triangle drawn, image stage.
DetectOptions point_sampling(int resolution) {
  DetectOptions o;
  o.conservative = false;
  o.theta = o.phi = o.roll = 0.0;
  o.ids = IdMode::unique;
  o.peel = PeelMode::full;
  o.slope = 0.0;
  o.views = 1;
  o.cull = Cull::box;
  o.stage = Stage::image;
  o.resolution = resolution;
  return o;
}

Explanation explain_pair(const std::vector<Object>& objects, const DetectOptions& options, const PairQuery& q) {
  Detector detector(std::make_shared<CpuImageStage>());
  const FrameTrace trace(detector, objects, options);
  return trace.explain(q);
}

// The exact contacts between A's triangles in [a0, a1) and B's in [b0, b1): the longest.
PairQuery longest_contact(const std::vector<Object>& objects, std::uint32_t a0, std::uint32_t a1, std::uint32_t b0,
                          std::uint32_t b1) {
  PairQuery best{0, 1, 0, 0};
  double length = -1.0;
  for (const std::uint64_t k : exact_colliding_pairs(objects[0].mesh, objects[1].mesh)) {
    const std::uint32_t ta = pair_a(k), tb = pair_b(k);
    if (ta < a0 || ta >= a1 || tb < b0 || tb >= b1) continue;
    const auto s = intersection_segment(corners(objects[0].mesh, ta), corners(objects[1].mesh, tb));
    if ((s.second - s.first).norm() > length) length = (s.second - s.first).norm(), best = {0, 1, ta, tb};
  }
  REQUIRE(length >= 0.0);
  return best;
}

}  // namespace

TEST_CASE("explain: found, with the view and the texel", "[explain]") {
  Builder a("floor"), b("wall");
  a.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  b.quad({0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o;  // the default configuration, the image stage forced
  o.stage = Stage::image;
  const PairQuery q = longest_contact(objects, 0, 2, 0, 2);
  const Explanation e = explain_pair(objects, o, q);
  CHECK(e.intersect);
  CHECK(e.kind == "crossing");
  CHECK(e.reported);
  CHECK(e.verdict == Verdict::found);
  REQUIRE(e.views.size() == 1);
  CHECK(e.views[0].reason == Verdict::found);
  CHECK(e.views[0].found_texels > 0);
  CHECK(e.views[0].found_x >= 0);
  CHECK(e.verdict_line.find("found in view 0 at texel") == 0);
  // Under the router on a CPU stage the same pair goes through the exact path.
  DetectOptions routed;
  routed.stage = Stage::exact;
  const Explanation x = explain_pair(objects, routed, q);
  CHECK(x.verdict == Verdict::found_exact);
  CHECK(x.views.empty());
}

TEST_CASE("explain: culled (contact culling drops a triangle that touches nothing of the other)", "[explain]") {
  Builder a("floor"), b("wall");
  a.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  const std::uint32_t far_a = a.tri({0.7, -0.8, -0.8}, {0.8, -0.8, -0.8}, {0.7, -0.7, -0.8});
  b.quad({0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1});
  const std::uint32_t far_b = b.tri({0.5, 0.5, 0.9}, {0.9, 0.5, 0.9}, {0.5, 0.9, 0.9});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o;
  o.stage = Stage::image;
  const Explanation e = explain_pair(objects, o, {0, 1, far_a, far_b});
  CHECK_FALSE(e.intersect);
  CHECK_FALSE(e.kept_a);
  CHECK(e.cull_a.find("contact culling") != std::string::npos);
  CHECK(e.verdict == Verdict::culled);
  CHECK(e.verdict_line.find("do not intersect") != std::string::npos);
  // A colliding pair of the same frame is kept: culling is conservative.
  const Explanation kept = explain_pair(objects, o, longest_contact(objects, 0, 2, 0, 2));
  CHECK(kept.kept_a);
  CHECK(kept.kept_b);
  CHECK(kept.verdict == Verdict::found);
}

TEST_CASE("explain: edge-on in two views, found in the third", "[explain]") {
  Builder a("floor"), b("slope");
  a.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});  // z = 0: edge-on along x and along y
  const auto z = [](double x, double y) { return 0.5 * x + 0.3 * y; };
  b.quad({-1, -1, z(-1, -1)}, {1, -1, z(1, -1)}, {1, 1, z(1, 1)}, {-1, 1, z(-1, 1)});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o = point_sampling(64);
  o.views = 3;  // along x, y and z
  o.slope = 1.0;
  const Explanation e = explain_pair(objects, o, longest_contact(objects, 0, 2, 0, 2));
  REQUIRE(e.views.size() == 3);
  CHECK(e.views[0].reason == Verdict::edge_on);
  CHECK(e.views[0].drawn_a);
  CHECK(e.views[0].fragments_a == 0);
  CHECK(e.views[1].reason == Verdict::edge_on);
  CHECK(e.views[2].reason == Verdict::found);
  CHECK(e.verdict == Verdict::found);
  CHECK(e.verdict_line.find("found in view 2") == 0);
  // With view 0 alone the pair is missed, edge-on.
  o.views = 1;
  const Explanation one = explain_pair(objects, o, longest_contact(objects, 0, 2, 0, 2));
  CHECK_FALSE(one.reported);
  CHECK(one.verdict == Verdict::edge_on);
  CHECK(one.verdict_line.find("edge-on") != std::string::npos);
}

TEST_CASE("explain: separated by a layer of the same object under alternate peeling", "[explain]") {
  // Along x: A = sheets at x = 0.6 and x = 1; B = a sheet at x = 0.9 over y < 0 and a sheet
  // crossing A's second one along y = 0 (x = 1 + y / 2). On y < 0, B's near sheet hides its
  // crossing one; on y > 0, A's near sheet hides its far one. Full peeling sees the crossing.
  Builder a("a"), b("b");
  a.quad({0.6, -1, -1}, {0.6, 1, -1}, {0.6, 1, 1}, {0.6, -1, 1});
  const std::uint32_t a2 = a.quad({1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1});
  b.quad({0.9, -1, -1}, {0.9, 0, -1}, {0.9, 0, 1}, {0.9, -1, 1});
  const std::uint32_t b2 = b.quad({0.5, -1, -1}, {1.5, 1, -1}, {1.5, 1, 1}, {0.5, -1, 1});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o = point_sampling(64);
  o.peel = PeelMode::alternate;
  const PairQuery q = longest_contact(objects, a2, a2 + 2, b2, b2 + 2);
  const Explanation e = explain_pair(objects, o, q);
  INFO(explain_text(e));
  CHECK(e.intersect);
  CHECK_FALSE(e.reported);
  REQUIRE(e.views.size() == 1);
  CHECK(e.views[0].common_texels > 0);
  CHECK(e.views[0].reason == Verdict::separated);
  CHECK(e.verdict == Verdict::separated);
  bool hidden_by_same_object = false;
  for (const TexelReport& t : e.views[0].texels)
    if (t.status == Verdict::separated && t.note.find("was not peeled here") != std::string::npos) hidden_by_same_object = true;
  CHECK(hidden_by_same_object);
  o.peel = PeelMode::full;
  CHECK(explain_pair(objects, o, q).verdict == Verdict::found);
}

TEST_CASE("explain: depth difference above epsilon, by how much", "[explain]") {
  // Two sheets crossing at a shallow angle (1 in 20) along y = 0.01, epsilon far below the depth
  // difference at the nearest texel centre.
  Builder a("a"), b("b");
  a.quad({1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1});
  const auto x = [](double y) { return 1.0 + 0.05 * (y - 0.01); };
  b.quad({x(-1), -1, -1}, {x(1), 1, -1}, {x(1), 1, 1}, {x(-1), -1, 1});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o = point_sampling(64);
  o.epsilon = 1e-6;
  const PairQuery q = longest_contact(objects, 0, 2, 0, 2);
  const Explanation e = explain_pair(objects, o, q);
  CHECK_FALSE(e.reported);
  CHECK(e.verdict == Verdict::above_epsilon);
  REQUIRE(e.views.size() == 1);
  bool measured = false;
  for (const TexelReport& t : e.views[0].texels)
    for (const TexelTest& test : t.tests)
      if (test.adjacent && !test.pass) {
        CHECK(test.value > test.bound);
        measured = true;
      }
  CHECK(measured);
  CHECK(e.verdict_line.find("above the threshold by") != std::string::npos);
  // One texel of epsilon (the default) finds it.
  o.epsilon = 0.0;
  CHECK(explain_pair(objects, o, q).verdict == Verdict::found);
}

TEST_CASE("explain: sub-texel (tile too coarse), found with --conservative", "[explain]") {
  // Two triangles 0.05 across crossing near the origin, in objects whose boxes span [-8, 8]^3:
  // a 16 x 16 tile has texels about a unit wide and no centre falls on either triangle.
  Builder a("a"), b("b");
  a.tri({-8, -8, -8}, {-7, -8, -8}, {-8, -7, -8});
  a.tri({8, 8, 8}, {7, 8, 8}, {8, 7, 8});
  const std::uint32_t ta = a.tri({0, 0.1, 0.1}, {0, 0.15, 0.1}, {0, 0.1, 0.15});
  b.tri({8, -8, -8}, {7, -8, -8}, {8, -7, -8});
  b.tri({-8, 8, 8}, {-7, 8, 8}, {-8, 7, 8});
  const std::uint32_t tb = b.tri({-0.02, 0.12, 0.09}, {0.02, 0.12, 0.09}, {0, 0.12, 0.16});
  const std::vector<Object> objects = {a.o, b.o};
  DetectOptions o = point_sampling(16);
  const PairQuery q{0, 1, ta, tb};
  const Explanation e = explain_pair(objects, o, q);
  REQUIRE(e.intersect);
  CHECK_FALSE(e.reported);
  CHECK(e.verdict == Verdict::sub_texel);
  CHECK(e.verdict_line.find("tile too coarse") != std::string::npos);
  REQUIRE(e.views.size() == 1);
  CHECK(e.views[0].segment_texels < 1.0);
  o.conservative = true;
  const Explanation c = explain_pair(objects, o, q);
  CHECK(c.verdict == Verdict::found);
  REQUIRE(c.views.size() == 1);
  CHECK(c.views[0].fragments_a > 0);
}

TEST_CASE("explain: --pair parsing, JSON and the page", "[explain]") {
  Builder a("floor"), b("wall");
  a.quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
  b.quad({0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1});
  const std::vector<Object> objects = {a.o, b.o};
  const PairQuery q = parse_pair_query("wall:1,floor:0", objects);
  CHECK(q.object_a == 1);
  CHECK(q.tri_a == 1);
  CHECK(q.object_b == 0);
  CHECK(parse_pair_query("0:1,1:0", objects).tri_b == 0);
  CHECK_THROWS_AS(parse_pair_query("floor:2,wall:0", objects), InputError);  // out of range
  CHECK_THROWS_AS(parse_pair_query("roof:0,wall:0", objects), InputError);   // no such object
  CHECK_THROWS_AS(parse_pair_query("floor:0", objects), InputError);
  CHECK_THROWS_AS(parse_pair_query("floor:0,floor:0", objects), InputError);  // a triangle with itself
  CHECK(parse_pair_query("floor:0,floor:1", objects).object_a == 0);  // a self pair: explain() checks "self"
  CHECK_THROWS_AS(parse_pair_query("floor:x,wall:0", objects), InputError);

  DetectOptions o;
  o.stage = Stage::image;
  const Explanation e = explain_pair(objects, o, longest_contact(objects, 0, 2, 0, 2));
  const nlohmann::json j = to_json(e);
  CHECK(j["schema"] == "peelcd.explain/1");
  CHECK(j["verdict"] == "found");
  CHECK(j["exact"]["intersect"] == true);
  CHECK(j["views"].size() == 1);
  CHECK(j["views"][0]["texels"].size() > 0);
  CHECK(explain_text(e).find("verdict: found") != std::string::npos);

  const fs::path dir = fs::temp_directory_path() / "peelcd_explain_page_test";
  fs::remove_all(dir);
  write_explain_page(e, dir.string());
  CHECK(fs::exists(dir / "index.html"));
  CHECK(fs::exists(dir / "view0.png"));
  CHECK(fs::exists(dir / "explain.json"));
  CHECK_FALSE(fs::exists(dir.string() + ".partial"));
  CHECK_THROWS_AS(write_explain_page(e, dir.string()), InputError);  // not empty: refused
  fs::remove_all(dir);
}
