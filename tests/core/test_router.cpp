// The stage router (DetectOptions::stage): the exact CPU path finds exactly the exact contacts
// on every class of geometry, whatever the image configuration; Stage::automatic follows the
// stage's cost model ROI by ROI and never loses a contact.
#include "peelcd/core/cpu_stage.h"
#include "peelcd/core/detector.h"
#include "peelcd/core/reference.h"
#include "peelcd/eval/classes.h"

#include <catch2/catch.hpp>

using namespace peelcd;

namespace {

// The CPU stage with a cost model chosen by the test.
class CostedStage final : public ImageStage {
 public:
  explicit CostedStage(StageCost cost) : cost_(cost) {}
  const std::string& backend() const override { return inner_.backend(); }
  const std::string& renderer() const override { return inner_.renderer(); }
  const std::string& version() const override { return inner_.version(); }
  int max_resolution() const override { return inner_.max_resolution(); }
  StageCost cost() const override { return cost_; }
  void peel(const PeelJob& job, PeelResult& out, Timings& t) override {
    ++peeled;
    inner_.peel(job, out, t);
  }
  std::size_t peeled = 0;

 private:
  CpuImageStage inner_;
  StageCost cost_;
};

std::vector<std::uint64_t> keys(const std::vector<Contact>& c) {
  std::vector<std::uint64_t> k;
  for (const Contact& x : c) k.push_back(pack_pair(x.tri_a, x.tri_b));
  return k;
}

}  // namespace

TEST_CASE("the exact CPU path finds the exact contacts on every class", "[router][classes]") {
  Detector detector(std::make_shared<CpuImageStage>());
  for (const GeometryClass& g : geometry_classes(6)) {
    for (DetectOptions opt : {DetectOptions{}, paper_options()}) {  // the image options do not matter
      opt.stage = Stage::exact;
      const FrameResult r = detector.detect(g.objects, opt);
      REQUIRE(r.rois_peeled == 0);
      std::size_t exact_rois = 0;
      for (const PairResult& p : r.pairs) {
        INFO(g.name << ": " << g.objects[p.object_a].name << " x " << g.objects[p.object_b].name);
        CHECK(keys(p.colliding) == exact_colliding_pairs(g.objects[p.object_a].mesh, g.objects[p.object_b].mesh));
        exact_rois += p.exact_stage;
        CHECK(p.layers == 0);
      }
      CHECK(r.rois_exact == exact_rois);
    }
  }
}

TEST_CASE("auto follows the cost model and loses nothing", "[router]") {
  const std::vector<GeometryClass> classes = geometry_classes(6);
  struct Case {
    const char* name;
    StageCost image;
    bool expect_image;
  };
  // A free image stage takes every ROI; one that costs a second per view takes none.
  for (const Case& c : {Case{"free image stage", StageCost{0, 0, 0}, true}, Case{"costly image stage", StageCost{1000, 0, 0}, false}}) {
    auto stage = std::make_shared<CostedStage>(c.image);
    Detector detector(stage);
    for (const GeometryClass& g : classes) {
      for (DetectOptions opt : {DetectOptions{}, paper_options()}) {
        opt.stage = Stage::automatic;
        stage->peeled = 0;
        const FrameResult r = detector.detect(g.objects, opt);
        INFO(c.name << ", " << g.name << ", conservative " << opt.conservative);
        for (const PairResult& p : r.pairs) {
          if (p.triangles_in_roi_a == 0 || p.triangles_in_roi_b == 0 || p.region.empty()) continue;  // nothing to route
          CHECK(p.exact_stage == !c.expect_image);
          CHECK(p.predicted_exact_ms >= 0.0);
          CHECK((p.predicted_image_ms >= 1000.0) == !c.expect_image);
          // Routed to the exact path: every exact contact. Through the image stage in
          // conservative mode: the same set.
          if (p.exact_stage || opt.conservative)
            CHECK(keys(p.colliding) == exact_colliding_pairs(g.objects[p.object_a].mesh, g.objects[p.object_b].mesh));
        }
        if (!c.expect_image) CHECK(stage->peeled == 0);
      }
    }
  }
}

TEST_CASE("the router's models are positive and its choice depends on them only", "[router]") {
  const StageCost exact = exact_path_cost();
  CHECK(exact.triangle_us > 0.0);
  CpuImageStage cpu;
  const StageCost image = cpu.cost();
  CHECK(image.predict_ms(1000, 128 * 128) > 0.0);
  // Deterministic: the same frame routes the same way twice.
  Detector detector(std::make_shared<CpuImageStage>());
  const GeometryClass g = geometry_classes(6).back();  // the crowded grid: many ROIs
  const FrameResult a = detector.detect(g.objects, DetectOptions{});
  const FrameResult b = detector.detect(g.objects, DetectOptions{});
  REQUIRE(a.pairs.size() == b.pairs.size());
  for (std::size_t i = 0; i < a.pairs.size(); ++i) CHECK(a.pairs[i].exact_stage == b.pairs[i].exact_stage);
}
