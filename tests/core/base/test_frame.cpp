// A frame's request and result (peelcd/core/frame.h): the counters a frame starts from, the image
// work one result adds to another, a pair's path, the paper's options.
#include "peelcd/core/frame.h"
#include "peelcd/core/image/planner.h"

#include <catch2/catch.hpp>

using namespace peelcd;

TEST_CASE("FrameResult: reset_counters() zeroes every counter and timing, keeps the pairs' storage", "[frame]") {
  FrameResult r;
  r.pairs.resize(3);
  r.timings = Timings{1, 2, 3, 4, 5, 6};
  r.gl_passes = r.rois_peeled = r.triangles_uploaded = r.triangles_indexed = r.shape_uploads = 7;
  r.pcs_readbacks = r.views_exhaustive = r.rois_exact = 7;
  r.gl_draws = r.gl_dispatches = r.gl_readbacks = r.bytes_uploaded = r.bytes_read = r.geometry_bytes = 7;
  r.gl_deep_texels = r.views_host_resolved = 7;
  r.reset_counters();
  CHECK(r.timings.total == 0.0);
  CHECK(r.timings.gpu == 0.0);
  CHECK(r.gl_passes + r.rois_peeled + r.triangles_uploaded + r.triangles_indexed + r.shape_uploads == 0);
  CHECK(r.pcs_readbacks + r.views_exhaustive + r.rois_exact == 0);
  CHECK(r.gl_draws + r.gl_dispatches + r.gl_readbacks + r.bytes_uploaded + r.bytes_read + r.geometry_bytes == 0);
  CHECK(r.gl_deep_texels + r.views_host_resolved == 0);
  CHECK(r.pairs.size() == 3);  // the caller's pairs are the frame's to overwrite
}

TEST_CASE("FrameResult: add_image_work() adds another frame's image-stage work and times", "[frame]") {
  FrameResult a, b;
  a.gl_passes = 1;
  a.gl_draws = 2;
  a.timings.gpu = 1.5;
  a.timings.total = 10.0;
  b.gl_passes = 3;
  b.gl_draws = 4;
  b.rois_peeled = 5;
  b.bytes_read = 6;
  b.timings.gpu = 2.0;
  b.timings.upload = 0.5;
  b.timings.total = 99.0;
  a.add_image_work(b);
  CHECK(a.gl_passes == 4);
  CHECK(a.gl_draws == 6);
  CHECK(a.rois_peeled == 5);
  CHECK(a.bytes_read == 6);
  CHECK(a.timings.gpu == 3.5);
  CHECK(a.timings.upload == 0.5);
  CHECK(a.timings.total == 10.0);  // the caller's frame, not the inner one's
}

TEST_CASE("a pair's path names what tested it", "[frame]") {
  PairResult p;
  CHECK(std::string(pair_path(p)) == "none");
  p.exact_stage = true;
  CHECK(std::string(pair_path(p)) == "exact");
  p.exact_stage = false;
  p.views_peeled = 3;
  CHECK(std::string(pair_path(p)) == "image");
  p.views_exhaustive = 1;
  CHECK(std::string(pair_path(p)) == "image+exhaustive");
  p.views_exhaustive = 3;
  CHECK(std::string(pair_path(p)) == "exhaustive");
  CHECK_FALSE(pair_path_reason(p, DetectOptions{}).empty());
}

TEST_CASE("the paper's options: point sampling, alternate peeling, paper IDs, one view along x, the whole box", "[frame]") {
  const DetectOptions o = paper_options();
  CHECK_FALSE(o.conservative);
  CHECK(o.peel == PeelMode::alternate);
  CHECK(o.ids == IdMode::paper);
  CHECK(o.views == 1);
  CHECK(o.theta == 0.0);
  CHECK(o.phi == 0.0);
  CHECK(o.slope == 0.0);
  CHECK(o.cull == Cull::box);
  CHECK(o.stage == Stage::image);
}

TEST_CASE("the option words parse back to what they name", "[frame]") {
  for (const Stage s : {Stage::automatic, Stage::image, Stage::exact}) CHECK(parse_stage(to_string(s)) == s);
  for (const Cull c : {Cull::contact, Cull::box}) CHECK(parse_cull(to_string(c)) == c);
  for (const PeelMode m : {PeelMode::full, PeelMode::alternate}) CHECK(parse_peel_mode(to_string(m)) == m);
  CHECK_FALSE(parse_stage("sometimes").has_value());
  CHECK_FALSE(parse_cull("").has_value());
}
