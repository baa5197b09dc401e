// The GL counters of a frame (FrameResult::gl_draws, gl_dispatches, gl_readbacks, bytes_uploaded,
// bytes_read; peelcd/core/image/image_stage.h StageCounters): what they count, checked against what the
// frame must have done. They are the measure of the GPU work's constancy (docs/backends.md).
#include "gl_fixture.h"
#include "peelcd/core/primitives.h"
#include "peelcd/eval/scenes.h"

#include <array>

#include <catch2/catch.hpp>

using namespace peelcd;
using namespace peelcd::test;

namespace {

std::vector<Object> two_rigid_balls(const std::shared_ptr<const Mesh>& ball, double dx) {
  std::vector<Object> objects(2);
  for (int k = 0; k < 2; ++k) {
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translate(Vec3(k * dx, 0.01 * k, 0.0));
    objects[std::size_t(k)].name = k ? "b" : "a";
    objects[std::size_t(k)].mesh = transformed(*ball, Transform{});
    for (Vec3& v : objects[std::size_t(k)].mesh.vertices) v = pose * v;
    objects[std::size_t(k)].rigid = RigidMotion{ball, pose};
  }
  return objects;
}

}  // namespace

TEST_CASE("GL counters: a rigid shape's corners are uploaded once, then only per-view indices", "[gl][counters]") {
  // A fresh shape (never seen by the pipeline): its first frame uploads its corners.
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 12, 18));
  const std::vector<Object> objects = two_rigid_balls(ball, 1.5);
  DetectOptions opt;
  opt.stage = Stage::image;
  opt.views = 1;
  gl::GlOptions one_view;
  one_view.batch = false;  // the one-view path: rigid shapes drawn from their resident buffers
  test_pipeline().set_gl_options(one_view);
  const FrameResult first = test_pipeline().detect(objects, opt);
  const FrameResult second = test_pipeline().detect(objects, opt);
  test_pipeline().set_gl_options(gl::GlOptions{});
  REQUIRE(first.rois_peeled == 1);
  CHECK(first.shape_uploads == 1);  // one shape, shared by both objects
  CHECK(second.shape_uploads == 0);
  // The difference is the shape's corners (3 per triangle, 16 bytes each), and a PCS header or two
  // more where the first frame grew its buffers and peeled again.
  const std::size_t shape_bytes = ball->triangles.size() * 3 * 16;
  CHECK(first.bytes_uploaded - second.bytes_uploaded >= shape_bytes);
  CHECK(first.bytes_uploaded - second.bytes_uploaded <= shape_bytes + 64);
  // What the second frame uploads is indices (3 per drawn triangle, 4 bytes each) and a header.
  CHECK(second.triangles_uploaded == 0);
  CHECK(second.triangles_indexed > 0);
  INFO("second frame: " << second.bytes_uploaded << " bytes, " << second.triangles_indexed << " indexed, " << second.triangles_uploaded << " uploaded, draws " << second.gl_draws << ", readbacks " << second.gl_readbacks << ", passes " << second.gl_passes);
  CHECK(second.bytes_uploaded >= second.triangles_indexed * 12);
  CHECK(second.bytes_uploaded <= second.triangles_indexed * 12 + 64);
  CHECK(second.gl_draws >= 2);  // each object drawn at least once
  CHECK(second.gl_readbacks >= 1);
  CHECK(second.bytes_read > 0);
}

TEST_CASE("GL counters: the exact path and a frame without ROIs do no GL work", "[gl][counters]") {
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 8, 12));
  DetectOptions opt;
  opt.stage = Stage::exact;
  const FrameResult exact = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
  CHECK(!exact.pairs.empty());
  opt.stage = Stage::image;
  const FrameResult apart = test_pipeline().detect(two_rigid_balls(ball, 5.0), opt);
  CHECK(apart.pairs.empty());
  for (const FrameResult* r : {&exact, &apart}) {
    CHECK(r->gl_draws == 0);
    CHECK(r->gl_dispatches == 0);
    CHECK(r->gl_readbacks == 0);
    CHECK(r->bytes_uploaded == 0);
    CHECK(r->bytes_read == 0);
  }
}

TEST_CASE("GL counters: the batched conservative frame is a count pass and a fill pass for every view", "[gl][counters]") {
  DetectOptions opt;
  opt.stage = Stage::image;
  opt.views = 3;
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 10, 14));  // new to the stage
    gl::GlOptions o;
    o.resolve = resolve;
    test_pipeline().set_gl_options(o);
    // The count pass sizes the k-buffer: no frame draws again, the first one neither.
    const FrameResult first = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
    const FrameResult r = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
    test_pipeline().set_gl_options(gl::GlOptions{});
    INFO("resolve " << to_string(resolve));
    REQUIRE(r.rois_peeled == 3);
    CHECK(first.gl_draws == 2);
    CHECK(r.gl_draws == 2);
    // Both balls rigid: their triangles selected on the GPU (three dispatches), no mesh data
    // uploaded after the first frame.
    CHECK(first.geometry_bytes > 0);
    CHECK(r.geometry_bytes == 0);
    if (resolve == Resolve::host) {
      CHECK(r.gl_dispatches == 3);  // the selection, its contact-region round and its grid round
      CHECK(r.gl_readbacks == 4);   // the counts, the draw's command, the selected IDs, the fragments mapped
    } else {
      // The selection's three passes, the prefix sum's three, the resolve.
      CHECK(r.gl_dispatches == 7);
      // The fragments' total, the command, the PCS header, the views' depths, the PCS list; nothing
      // per texel (the counts stay on the GPU).
      CHECK(r.gl_readbacks == 5);
    }
  }
}

TEST_CASE("GL counters: coverage auto rasterizes unless the cost models say compute", "[gl][counters][coverage]") {
  // GlOptions::coverage auto (the default) follows CostModels::coverage (a calibration file's
  // choice): a conservative frame of draws, or of dispatches alone, with the same PCS.
  DetectOptions opt;
  opt.stage = Stage::image;
  opt.views = 3;
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 10, 14));
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    gl::GlOptions o;
    o.resolve = resolve;
    REQUIRE(o.coverage == Coverage::automatic);
    test_pipeline().set_gl_options(o);
    const FrameResult raster = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
    CostModels models;
    models.source = "test";
    models.image = test_pipeline().stage().cost();
    models.exact = exact_path_cost();
    models.coverage = "compute";
    test_pipeline().stage().set_cost_models(models);
    const FrameResult compute = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
    test_pipeline().stage().clear_cost_models();
    const FrameResult again = test_pipeline().detect(two_rigid_balls(ball, 1.5), opt);
    test_pipeline().set_gl_options(gl::GlOptions{});
    INFO("resolve " << to_string(resolve));
    REQUIRE(raster.rois_peeled == 3);
    CHECK(raster.gl_draws == 2);   // the count and fill draws
    CHECK(compute.gl_draws == 0);  // the count and fill dispatches instead
    CHECK(compute.gl_dispatches == raster.gl_dispatches + 2);
    CHECK(again.gl_draws == 2);
    REQUIRE(compute.pairs.size() == raster.pairs.size());
    for (std::size_t i = 0; i < raster.pairs.size(); ++i) {
      CHECK(compute.pairs[i].pcs == raster.pairs[i].pcs);
      CHECK(compute.pairs[i].colliding.size() == raster.pairs[i].colliding.size());
    }
  }
}

TEST_CASE("GL counters: draws, dispatches and readbacks per frame do not depend on the number of ROIs", "[gl][counters]") {
  // A pile of 4 balls (a few ROIs) and of 400 (about 1,800), the image stage forced, both image
  // modes (conservative, point sampling with the default single-pass peeler), both resolves:
  // after the first frame (which may grow the PCS list), the same GL calls, and no mesh data
  // uploaded for the rigid balls.
  const auto pile_counts = [](std::size_t balls, Resolve resolve, bool conservative) {
    const std::unique_ptr<Sequence> pile = make_crowd(balls, 3, true);
    gl::GlOptions o;
    o.resolve = resolve;
    test_pipeline().set_gl_options(o);
    DetectOptions opt;
    opt.stage = Stage::image;
    opt.conservative = conservative;
    std::vector<Object> objects;
    FrameResult r;
    std::array<std::size_t, 4> counts{};
    for (std::size_t f = 0; f < 3; ++f) {
      pile->frame(f, objects);
      test_pipeline().detect(objects, opt, r);
      counts = {r.gl_draws, r.gl_dispatches, r.gl_readbacks, r.rois_peeled};
      // Mesh data after the first frame: only the deforming balls' (every fifth ball breathes:
      // none of 4, 80 of 400), 3 corners of 16 bytes and one 16-byte entry per drawn triangle.
      if (f > 0) CHECK(r.geometry_bytes == r.triangles_uploaded * 64);
      if (f > 0 && balls == 4) CHECK(r.geometry_bytes == 0);
    }
    test_pipeline().set_gl_options(gl::GlOptions{});
    return counts;
  };
  for (const bool conservative : {true, false})
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    const auto few = pile_counts(4, resolve, conservative);
    const auto many = pile_counts(400, resolve, conservative);
    INFO((conservative ? "conservative" : "point sampling") << ", resolve " << to_string(resolve) << ": 4 balls "
         << few[3] << " views, 400 balls " << many[3] << " views");
    REQUIRE(many[3] > 100 * few[3] / 4);  // the pile really has many more ROI views
    CHECK(few[0] == many[0]);  // draws
    CHECK(few[1] == many[1]);  // dispatches
    CHECK(few[2] == many[2]);  // readbacks
  }
}

// The stage's clocks (Timings::gl_wait, and with pass timing gpu_raster / gpu_compute /
// gpu_transfer by GL timer queries): on when asked, zero when not, and never a change to what a
// frame finds. Both peelers and the batched conservative path.
TEST_CASE("GL clocks: pass timing measures the passes and leaves the results alone", "[gl][counters]") {
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 16, 24));
  const std::vector<Object> objects = two_rigid_balls(ball, 1.5);
  gl::GlImageStage& stage = test_pipeline().stage();
  for (const bool conservative : {true, false}) {
    for (const Peeler peeler : {Peeler::abuffer, Peeler::multipass}) {
      if (conservative && peeler == Peeler::multipass) continue;  // conservative views use the k-buffer
      DYNAMIC_SECTION((conservative ? "conservative" : "point sampled") << ", " << to_string(peeler)) {
        DetectOptions opt;
        opt.stage = Stage::image;
        opt.conservative = conservative;
        opt.views = conservative ? 3 : 1;
        gl::GlOptions gl_opt;
        gl_opt.peeler = peeler;
        test_pipeline().set_gl_options(gl_opt);
        stage.set_pass_timing(false);
        const FrameResult plain = test_pipeline().detect(objects, opt);
        stage.set_pass_timing(true);
        CHECK(stage.pass_timing());
        const FrameResult timed = test_pipeline().detect(objects, opt);
        const FrameResult timed_again = test_pipeline().detect(objects, opt);
        stage.set_pass_timing(false);
        const FrameResult after = test_pipeline().detect(objects, opt);
        test_pipeline().set_gl_options(gl::GlOptions{});
        REQUIRE(plain.rois_peeled >= 1);
        for (const FrameResult* t : {&plain, &after}) {  // nothing timed, nothing left over
          CHECK_FALSE(t->timings.gpu_timed);
          CHECK(t->timings.gpu_raster == 0.0);
          CHECK(t->timings.gpu_compute == 0.0);
          CHECK(t->timings.gpu_transfer == 0.0);
          CHECK(t->timings.gpu_select == 0.0);
          CHECK(t->timings.gpu_cover == 0.0);
        }
        for (const FrameResult* t : {&timed, &timed_again}) {
          CHECK(t->timings.gpu_timed);
          CHECK(t->timings.gpu_raster > 0.0);  // every frame draws
          CHECK(t->timings.gpu_compute >= 0.0);
          // The selection's and the compute coverage's passes are parts of compute (none of the
          // latter here: the default coverage rasterizes where these tests run, llvmpipe).
          CHECK(t->timings.gpu_select >= 0.0);
          CHECK(t->timings.gpu_cover >= 0.0);
          CHECK(t->timings.gpu_select + t->timings.gpu_cover <= t->timings.gpu_compute * (1 + 1e-12));
          CHECK(t->timings.gl_wait >= 0.0);
          CHECK(t->timings.gl_wait <= t->timings.total);
          // GPU passes in one stage call run one after the other: together no longer than the frame.
          CHECK(t->timings.gpu_raster + t->timings.gpu_compute + t->timings.gpu_transfer <= t->timings.total);
        }
        REQUIRE(timed.pairs.size() == plain.pairs.size());
        for (std::size_t i = 0; i < plain.pairs.size(); ++i) {
          CHECK(timed.pairs[i].pcs == plain.pairs[i].pcs);
          CHECK(timed.pairs[i].colliding.size() == plain.pairs[i].colliding.size());
        }
        CHECK(timed.gl_draws == plain.gl_draws);
        CHECK(timed.gl_dispatches == plain.gl_dispatches);
      }
    }
  }
}
