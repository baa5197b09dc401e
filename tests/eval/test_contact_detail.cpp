// DetectOptions::contacts: the pairs-only request gives the same colliding pairs, relations and
// depths as the full request on every class of peelcd/eval/classes.h, through the frame API's
// two paths and the World; its contacts hold no segment (kind unclassified) except those a pair's
// relation needed, and those are the full request's contacts.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/world/world.h"
#include "peelcd/eval/classes.h"
#include "stride.h"  // PEELCD_TEST_STRIDE

#include <cstdio>

#include <catch2/catch.hpp>
#include "fixtures.h"

using namespace peelcd;

namespace {

using test::cpu_detector;

// Every scene of the classes, with what it asks (self on its objects; depth on the depth classes).
struct Case {
  std::string name;
  std::vector<Object> objects;
  bool depth = false;
};
std::vector<Case> cases() {
  std::vector<Case> out;
  for (GeometryClass& c : geometry_classes(4)) out.push_back({c.name, std::move(c.objects)});
  for (GeometryClass& c : self_classes()) out.push_back({c.name, std::move(c.objects)});
  for (ContainmentClass& c : containment_classes()) out.push_back({c.scene.name, std::move(c.scene.objects)});
  for (DepthClass& c : depth_classes()) out.push_back({c.scene.name, std::move(c.scene.objects), true});
  return out;
}

// The pairs-only frame `got` against the full frame `full` of the same scene.
void check_same_answer(const FrameResult& full, const FrameResult& got, bool depth) {
  REQUIRE(got.pairs.size() == full.pairs.size());
  for (std::size_t p = 0; p < full.pairs.size(); ++p) {
    const PairResult& f = full.pairs[p];
    const PairResult& g = got.pairs[p];
    INFO("pair " << f.object_a << "-" << f.object_b);
    CHECK(g.object_a == f.object_a);
    CHECK(g.object_b == f.object_b);
    CHECK(g.relation == f.relation);
    CHECK(g.is_collision() == f.is_collision());
    REQUIRE(g.colliding.size() == f.colliding.size());
    bool unclassified = false, crossing = false;
    for (std::size_t k = 0; k < f.colliding.size(); ++k) {
      const Contact& a = f.colliding[k];
      const Contact& b = g.colliding[k];
      CHECK(a.tri_a == b.tri_a);
      CHECK(a.tri_b == b.tri_b);
      CHECK(a.classified());  // the full request classifies every contact
      if (b.classified()) {  // what the pairs-only request did classify is the full answer
        CHECK(b.kind == a.kind);
        CHECK(b.p == a.p);
        CHECK(b.q == a.q);
        crossing |= b.kind == ContactKind::crossing;
      } else {
        unclassified = true;
        CHECK(b.p == Vec3::Zero());
        CHECK(b.q == Vec3::Zero());
      }
    }
    // A contact is left unclassified only once a crossing one decides the relation.
    if (unclassified) CHECK(crossing);
    if (depth) {
      CHECK(g.depth.known == f.depth.known);
      CHECK(g.depth.depth == f.depth.depth);
    }
  }
}

}  // namespace

TEST_CASE("contacts pairs: the full request's pairs, relations and depths on every class, both paths", "[contacts]") {
  std::size_t unclassified = 0, contacts = 0;
  const std::vector<Case> all = cases();
  for (std::size_t i = 0; i < all.size(); ++i)
    for (const Stage stage : {Stage::exact, Stage::image}) {
      if (test::stride_skips(i)) continue;
      const Case& c = all[i];
      DetectOptions opt;
      opt.stage = stage;
      opt.depth = c.depth;
      INFO(c.name << ", stage " << to_string(stage));
      const FrameResult full = cpu_detector().detect(c.objects, opt);
      opt.contacts = ContactDetail::pairs;
      const FrameResult got = cpu_detector().detect(c.objects, opt);
      check_same_answer(full, got, c.depth);
      for (const PairResult& p : got.pairs)
        for (const Contact& k : p.colliding) unclassified += !k.classified(), ++contacts;
    }
  // The request must really leave contacts unclassified, or it saves nothing (pairs touching only
  // need every kind: the resting classes classify all theirs).
  std::printf("contacts pairs on the classes: %zu of %zu contacts unclassified\n", unclassified, contacts);
  CHECK(unclassified > 0);
}

TEST_CASE("contacts pairs: the World's pairs and relations are the full request's, rigid self caches included", "[contacts][world]") {
  for (const Case& c : cases()) {
    INFO(c.name);
    // Every object a rigid body at a pose (its shape in its own frame) and, asked, self.
    World world;
    const Eigen::Affine3d pose = Eigen::Translation3d(0.25, -0.5, 1.0) * Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized());
    for (const Object& o : c.objects) {
      Mesh shape = o.mesh;
      for (Vec3& v : shape.vertices) v = pose.inverse() * v;
      const BodyId id = world.add_rigid(std::make_shared<const Mesh>(std::move(shape)), pose);
      world.set_self(id, o.self);
    }
    DetectOptions opt;
    opt.stage = Stage::exact;
    // Full, pairs, full again: a rigid body's cached self contacts follow the request. (A first
    // frame before them: the World's first frame may bound a posed body by its tree's root box
    // carried through the pose, which can pair boxes the later frames' tighter ones do not.)
    world.collide(opt);
    const FrameResult full = world.collide(opt);
    opt.contacts = ContactDetail::pairs;
    const FrameResult got = world.collide(opt);
    check_same_answer(full, got, false);
    opt.contacts = ContactDetail::segments;
    const FrameResult again = world.collide(opt);
    REQUIRE(again.pairs.size() == full.pairs.size());
    for (std::size_t p = 0; p < full.pairs.size(); ++p) {
      REQUIRE(again.pairs[p].colliding.size() == full.pairs[p].colliding.size());
      for (std::size_t k = 0; k < full.pairs[p].colliding.size(); ++k) {
        CHECK(again.pairs[p].colliding[k].kind == full.pairs[p].colliding[k].kind);
        CHECK(again.pairs[p].colliding[k].p == full.pairs[p].colliding[k].p);
      }
    }
  }
}
