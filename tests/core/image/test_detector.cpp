// peelcd::Detector (the frame API, peelcd/core/image/detector.h) on the CPU image stage: the frame's
// plan (its pairs, routes and views), the views it peels are those for_each_view() names, a
// reused result holds the latest frame alone, only_pairs() restricts a frame, and the three
// stages give the exact pairs.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/reference.h"

#include <catch2/catch.hpp>

#include <memory>

using namespace peelcd;

namespace {

// The CPU stage, recording every job it is given.
class RecordingStage : public ImageStage {
 public:
  std::vector<PeelJob> jobs;
  std::vector<std::vector<std::uint32_t>> triangles;  // per job: A's, then B's
  const std::string& backend() const override { return inner_.backend(); }
  const std::string& renderer() const override { return inner_.renderer(); }
  const std::string& version() const override { return inner_.version(); }
  int max_resolution() const override { return inner_.max_resolution(); }
  StageCost cost() const override { return inner_.cost(); }
  void peel(const PeelJob& job, PeelResult& out, Timings& timings) override {
    jobs.push_back(job);
    triangles.push_back(*job.triangles[0]);
    triangles.push_back(*job.triangles[1]);
    inner_.peel(job, out, timings);
  }

 private:
  CpuImageStage inner_;
};


// Three spheres in a row, each crossing the next; a fourth far away.
std::vector<Object> row_of_spheres() {
  std::vector<Object> v;
  for (int i = 0; i < 3; ++i) v.push_back(named_object("s" + std::to_string(i), make_uv_sphere(Vec3(1.5 * i, 0.1 * i, 0), 1.0, 14, 18)));
  v.push_back(named_object("far", make_box(Vec3(20, 20, 20), Vec3(21, 21, 21))));
  return v;
}

std::vector<std::uint64_t> keys(const PairResult& r) {
  std::vector<std::uint64_t> k;
  for (const Contact& c : r.colliding) k.push_back(pack_pair(c.tri_a, c.tri_b));
  return k;
}

}  // namespace

TEST_CASE("Detector: every stage finds exactly the reference's pairs, pair by pair", "[detector]") {
  const std::vector<Object> objects = row_of_spheres();
  Detector d(std::make_shared<CpuImageStage>());
  for (const Stage stage : {Stage::automatic, Stage::exact, Stage::image}) {
    DetectOptions opt;
    opt.stage = stage;
    const FrameResult r = d.detect(objects, opt);
    REQUIRE(r.pairs.size() == 2);  // (0, 1) and (1, 2); the far box overlaps nothing
    for (const PairResult& p : r.pairs) {
      CHECK(p.object_b == p.object_a + 1);
      CHECK(keys(p) == exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh));
      CHECK(p.exact_stage == (stage == Stage::exact || (stage == Stage::automatic && p.predicted_exact_ms <= p.predicted_image_ms)));
    }
    if (stage == Stage::image) CHECK(r.rois_peeled > 0);
    if (stage == Stage::exact) CHECK(r.rois_exact == 2);
  }
}

TEST_CASE("Detector: the views a frame peels are the views for_each_view() names", "[detector]") {
  const std::vector<Object> objects = row_of_spheres();
  auto stage = std::make_shared<RecordingStage>();
  Detector d(stage);
  for (const int views : {1, 3}) {
    DetectOptions opt;
    opt.stage = Stage::image;
    opt.views = views;
    stage->jobs.clear();
    stage->triangles.clear();
    d.detect(objects, opt);
    const std::vector<PeelJob> peeled = stage->jobs;
    const auto peeled_tris = stage->triangles;
    std::size_t k = 0;
    d.for_each_view(objects, opt, [&](const PeelJob& job) {
      REQUIRE(k < peeled.size());
      const PeelJob& p = peeled[k];
      CHECK(job.pair_index == p.pair_index);
      CHECK(job.view_index == p.view_index);
      CHECK(job.view.box.lo == p.view.box.lo);
      CHECK(job.view.box.hi == p.view.box.hi);
      CHECK(job.view.resolution == p.view.resolution);
      CHECK(job.epsilon == p.epsilon);
      CHECK(job.first == p.first);
      CHECK(job.objects[0] == p.objects[0]);
      CHECK(job.objects[1] == p.objects[1]);
      CHECK(*job.triangles[0] == peeled_tris[2 * k]);
      CHECK(*job.triangles[1] == peeled_tris[2 * k + 1]);
      ++k;
    });
    CHECK(k == peeled.size());
    CHECK(k == std::size_t(2 * views));  // two pairs, `views` views each
  }
}

TEST_CASE("Detector: for_each_view() routes as detect() does", "[detector]") {
  const std::vector<Object> objects = row_of_spheres();
  auto stage = std::make_shared<RecordingStage>();
  Detector d(stage);
  DetectOptions opt;  // Stage::automatic: the CPU stage's model sends these small pairs to the exact path
  const FrameResult r = d.detect(objects, opt);
  std::size_t peeled_pairs = 0;
  for (const PairResult& p : r.pairs) peeled_pairs += p.exact_stage ? 0 : 1;
  std::size_t named = 0;
  d.for_each_view(objects, opt, [&](const PeelJob&) { ++named; });
  CHECK(named == stage->jobs.size());
  CHECK((named == 0) == (peeled_pairs == 0));
}

TEST_CASE("Detector: a reused result holds the latest frame alone", "[detector]") {
  std::vector<Object> objects = row_of_spheres();
  Detector d(std::make_shared<CpuImageStage>());
  DetectOptions image;
  image.stage = Stage::image;
  FrameResult out;
  d.detect(objects, image, out);
  REQUIRE(out.pairs.size() == 2);
  CHECK(out.rois_peeled > 0);
  // The next frame: one pair, on the exact path; nothing of the first frame remains.
  objects.pop_back();
  objects.pop_back();
  DetectOptions exact;
  exact.stage = Stage::exact;
  d.detect(objects, exact, out);
  REQUIRE(out.pairs.size() == 1);
  CHECK(out.rois_peeled == 0);
  CHECK(out.rois_exact == 1);
  CHECK(out.gl_passes == 0);
  CHECK(out.pairs[0].pcs.empty());
  CHECK(out.pairs[0].layers == 0);
  CHECK(keys(out.pairs[0]) == exact_colliding_pairs(objects[0].mesh, objects[1].mesh));
}

TEST_CASE("Detector: only_pairs() restricts a frame to the listed pairs", "[detector]") {
  const std::vector<Object> objects = row_of_spheres();
  Detector d(std::make_shared<CpuImageStage>());
  const std::vector<std::pair<std::size_t, std::size_t>> only = {{1, 2}, {2, 3}};  // (2, 3) does not overlap
  d.only_pairs(&only);
  FrameResult r = d.detect(objects, DetectOptions{});
  REQUIRE(r.pairs.size() == 1);
  CHECK(r.pairs[0].object_a == 1);
  CHECK(r.pairs[0].object_b == 2);
  d.only_pairs(nullptr);
  r = d.detect(objects, DetectOptions{});
  CHECK(r.pairs.size() == 2);
}

TEST_CASE("Detector: the route follows the stage's cost models", "[detector]") {
  const std::vector<Object> objects = row_of_spheres();
  auto stage = std::make_shared<CpuImageStage>();
  Detector d(stage);
  CostModels models;
  models.source = "test";
  models.exact = StageCost{0.0, 1.0, 0.0, 0.0};
  models.image = StageCost{1e6, 0.0, 0.0, 0.0};  // a view costs a thousand seconds: exact
  stage->set_cost_models(models);
  FrameResult r = d.detect(objects, DetectOptions{});
  for (const PairResult& p : r.pairs) CHECK(p.exact_stage);
  models.exact = StageCost{1e6, 0.0, 0.0, 0.0};
  models.image = StageCost{0.0, 1e-3, 0.0, 0.0};  // now the exact path is the dear one
  stage->set_cost_models(models);
  r = d.detect(objects, DetectOptions{});
  for (const PairResult& p : r.pairs) {
    CHECK_FALSE(p.exact_stage);
    CHECK(p.predicted_image_ms < p.predicted_exact_ms);
    CHECK(keys(p) == exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh));
  }
  stage->clear_cost_models();
}
