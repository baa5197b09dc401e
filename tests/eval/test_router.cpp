// The stage router (DetectOptions::stage): the exact CPU path finds exactly the exact contacts
// on every class of geometry, whatever the image configuration; Stage::automatic follows the
// stage's cost model ROI by ROI and never loses a contact.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/eval/classes.h"
#include "peelcd/eval/scenes.h"

#include <catch2/catch.hpp>

#include <algorithm>

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

// An image stage whose fixed cost per view lies between the exact path's smallest and largest
// predictions on `objects` (without the scan both paths pay): ROIs go to each stage.
StageCost mixed_cost(const std::vector<Object>& objects) {
  Detector probe(std::make_shared<CpuImageStage>());
  std::vector<double> exact;
  const double scan_us = exact_path_cost().scan_us;
  for (const PairResult& p : probe.detect(objects, DetectOptions{}).pairs) {
    const double scan =
        scan_us * 1e-3 * double(objects[p.object_a].mesh.triangles.size() + objects[p.object_b].mesh.triangles.size());
    if (p.predicted_exact_ms > 0.0) exact.push_back(p.predicted_exact_ms - scan);
  }
  if (exact.empty()) return StageCost{0, 0, 0};
  const auto [lo, hi] = std::minmax_element(exact.begin(), exact.end());
  return StageCost{0.5 * (*lo + *hi), 0.0, 0.0};
}

// The classes of geometry and a frame of the 60-ball pile (overlaps of many sizes).
std::vector<std::pair<std::string, std::vector<Object>>> thread_scenes() {
  std::vector<std::pair<std::string, std::vector<Object>>> out;
  for (GeometryClass& g : geometry_classes(8)) out.emplace_back(g.name, std::move(g.objects));
  std::vector<Object> pile;
  make_crowd(60, 3)->frame(2, pile);
  out.emplace_back("60-ball pile", std::move(pile));
  return out;
}

TEST_CASE("culling and the exact CPU path give the same frame on 1, 2 and 4 threads", "[router][threads]") {
  // A mixed router: ROIs go to each stage, so every parallel loop runs (culling twice, the exact
  // path), with the image stage's ROIs between them.
  for (const auto& [name, objects] : thread_scenes()) {
    auto stage = std::make_shared<CostedStage>(mixed_cost(objects));
    Detector detector(stage);
    DetectOptions opt;
    opt.threads = 1;
    const FrameResult one = detector.detect(objects, opt);
    for (const unsigned threads : {2u, 4u, 0u}) {
      opt.threads = threads;
      for (int repeat = 0; repeat < 2; ++repeat) {  // a second frame reuses the pool and the lanes
        const FrameResult many = detector.detect(objects, opt);
        INFO(name << ", threads " << threads << ", frame " << repeat);
        CHECK(many.rois_exact == one.rois_exact);
        CHECK(many.rois_peeled == one.rois_peeled);
        REQUIRE(many.pairs.size() == one.pairs.size());
        for (std::size_t i = 0; i < one.pairs.size(); ++i) {
          const PairResult &x = one.pairs[i], &y = many.pairs[i];
          CHECK(y.object_a == x.object_a);
          CHECK(y.object_b == x.object_b);
          CHECK(y.exact_stage == x.exact_stage);
          CHECK(y.resolution == x.resolution);
          CHECK(y.candidates == x.candidates);
          CHECK(y.triangles_in_roi_a == x.triangles_in_roi_a);
          CHECK(keys(y.colliding) == keys(x.colliding));
        }
      }
    }
  }
}

TEST_CASE("a mixed frame of the ball pile routes some ROIs each way", "[router][threads]") {
  // Guards the test above: with its model both stages get ROIs of the pile.
  const std::vector<Object> pile = thread_scenes().back().second;
  Detector detector(std::make_shared<CostedStage>(mixed_cost(pile)));
  const FrameResult r = detector.detect(pile, DetectOptions{});
  CHECK(r.rois_exact > 0);
  CHECK(r.rois_peeled > 0);
}

TEST_CASE("cost models set on a stage (a calibration file's) drive the router, the built-in ones otherwise", "[router][costs]") {
  const GeometryClass g = geometry_classes(6).back();  // the crowded grid: many ROIs
  auto stage = std::make_shared<CpuImageStage>();
  Detector detector(stage);
  const auto routed_to_image = [&] {
    std::size_t image = 0, pairs = 0;
    for (const PairResult& p : detector.detect(g.objects, DetectOptions{}).pairs) {
      if (p.candidates == 0 && p.colliding.empty() && p.predicted_exact_ms == 0.0) continue;  // culled out
      ++pairs;
      image += p.exact_stage ? 0 : 1;
    }
    return std::make_pair(image, pairs);
  };
  CostModels free_image;  // the image stage free, the exact path dear: every ROI to the image stage
  free_image.source = "test: image free";
  free_image.image = StageCost{0, 0, 0, 0};
  free_image.exact = StageCost{1000, 1000, 0, 0};
  stage->set_cost_models(free_image);
  const auto [image_all, pairs_all] = routed_to_image();
  REQUIRE(pairs_all > 0);
  CHECK(image_all == pairs_all);
  CostModels free_exact = free_image;  // and the other way round
  free_exact.image = StageCost{1000, 1000, 1000, 0};
  free_exact.exact = StageCost{0, 0, 0, 0};
  stage->set_cost_models(free_exact);
  CHECK(routed_to_image().first == 0);
  stage->clear_cost_models();  // the built-in models again
  CHECK(stage->router_exact_cost().triangle_us == exact_path_cost().triangle_us);
  CHECK(stage->router_image_cost().triangle_us == stage->cost().triangle_us);
}
