// The default scene (docs/design.md section 4) at 256^2 with paper IDs, over several views: no false
// contact ever, and the miss ratio of the default configuration under 15% in every view.
#include "gl_fixture.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>

using namespace peelcd;
using namespace peelcd::test;

namespace {
const std::vector<Object>& scene() {
  static const std::vector<Object> objects = load_objects(load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json"));
  return objects;
}
const std::vector<std::uint64_t>& exact() {
  static const std::vector<std::uint64_t> pairs = exact_colliding_pairs(scene()[0].mesh, scene()[1].mesh);
  return pairs;
}
const std::vector<std::pair<double, double>> kViews = {{0, 0}, {90, 0}, {45, 30}, {0, 90}, {200, -40}, {300, 60}, {150, -90}};
}  // namespace

TEST_CASE("bunny vs dragon: the exact reference finds docs/design.md's 228 pairs", "[bunny_dragon]") {
  CHECK(exact().size() == 228);
}

TEST_CASE("bunny vs dragon at 256^2, paper IDs: no false contact, miss ratio under 15% per view", "[bunny_dragon]") {
  DetectOptions opt;  // one view, full peeling, slope-following epsilon, the paper's IDs
  opt.stage = Stage::image;  // the image stage is what this checks
  opt.resolution = 256;
  opt.ids = IdMode::paper;
  opt.peel = PeelMode::full;
  opt.slope = 1.0;
  opt.views = 1;
  for (const auto& [theta, phi] : kViews) {
    opt.theta = theta;
    opt.phi = phi;
    const FrameResult f = test_pipeline().detect(scene(), opt);
    REQUIRE(f.pairs.size() == 1);
    const Score s = score(exact(), f.pairs[0].colliding);
    std::printf("bunny-dragon 256 paper-ids full slope=1 theta=%5.1f phi=%5.1f: found %3zu/%zu miss %5.2f%% false %zu\n",
                theta, phi, s.found, s.exact, 100 * s.miss_ratio(), s.false_contacts);
    INFO("theta " << theta << " phi " << phi << " miss ratio " << s.miss_ratio());
    CHECK(s.false_contacts == 0);
    CHECK(s.miss_ratio() < 0.15);
  }
}

TEST_CASE("bunny vs dragon: the paper's mode is reported, and full peeling's PCS contain it", "[bunny_dragon]") {
  DetectOptions paper;
  paper.stage = Stage::image;  // the image stage is what this checks
  paper.resolution = 256;
  paper.ids = IdMode::paper;
  paper.peel = PeelMode::alternate;
  paper.slope = 0.0;  // the paper: constant epsilon of one texel
  paper.views = 1;
  for (const auto& [theta, phi] : kViews) {
    paper.theta = theta;
    paper.phi = phi;
    DetectOptions full = paper;
    full.peel = PeelMode::full;
    const PairResult a = test_pipeline().detect(scene(), paper).pairs.at(0);
    const PairResult b = test_pipeline().detect(scene(), full).pairs.at(0);
    const Score sa = score(exact(), a.colliding), sb = score(exact(), b.colliding);
    std::printf("bunny-dragon 256 paper-ids alternate slope=0 theta=%5.1f phi=%5.1f: miss %5.2f%%  (full: %5.2f%%)\n",
                theta, phi, 100 * sa.miss_ratio(), 100 * sb.miss_ratio());
    INFO("theta " << theta << " phi " << phi);
    CHECK(sa.false_contacts == 0);
    CHECK(sb.false_contacts == 0);
    CHECK(std::includes(b.pcs.begin(), b.pcs.end(), a.pcs.begin(), a.pcs.end()));
    CHECK(sb.found >= sa.found);
  }
}

TEST_CASE("bunny vs dragon: fused views only add PCS, one view to two to three", "[bunny_dragon]") {
  DetectOptions opt;  // the default configuration at 128^2
  opt.stage = Stage::image;  // the image stage is what this checks
  opt.resolution = 128;
  for (const auto& [theta, phi] : kViews) {
    opt.theta = theta;
    opt.phi = phi;
    std::vector<PairResult> by_views;
    for (int views = 1; views <= 3; ++views) {
      opt.views = views;
      by_views.push_back(test_pipeline().detect(scene(), opt).pairs.at(0));
    }
    INFO("theta " << theta << " phi " << phi);
    for (int k = 0; k < 2; ++k) {
      const PairResult &fewer = by_views[k], &more = by_views[k + 1];
      CHECK(std::includes(more.pcs.begin(), more.pcs.end(), fewer.pcs.begin(), fewer.pcs.end()));
      const auto pairs = [](const PairResult& r) {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
        for (const Contact& c : r.colliding) out.emplace_back(c.tri_a, c.tri_b);
        return out;  // sorted: colliding is
      };
      const auto found_more = pairs(more), found_fewer = pairs(fewer);
      CHECK(std::includes(found_more.begin(), found_more.end(), found_fewer.begin(), found_fewer.end()));
      CHECK(score(exact(), more.colliding).false_contacts == 0);
    }
    std::printf("bunny-dragon 128 default theta=%5.1f phi=%5.1f: miss 1 view %5.2f%%, 2 views %5.2f%%, 3 views %5.2f%%\n",
                theta, phi, 100 * score(exact(), by_views[0].colliding).miss_ratio(),
                100 * score(exact(), by_views[1].colliding).miss_ratio(),
                100 * score(exact(), by_views[2].colliding).miss_ratio());
  }
}
