// Texels deeper than one GPU-resolve invocation takes (PEELCD_GPU_RESOLVE_DEPTH fragments,
// peelcd/core/image/pcs_test.inc): the GPU resolve gives the host resolve's PCS and misses nothing,
// batched (the deep texels split over invocations) and one view at a time (the view resolved on
// the host, counted), in both image modes. A fan of 256 triangles pierced at its centre by the
// tip of a 384-triangle cone puts every triangle of both in one texel; the default scene at a
// 1-texel tile puts every drawn triangle of two real meshes there.
#include "gl_fixture.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

using namespace peelcd;
using namespace peelcd::test;

namespace {

// A flat disc of `n` triangles around the origin in the plane z = 0.
Mesh fan(int n, double radius) {
  Mesh m;
  m.vertices.push_back(Vec3::Zero());
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * (k + 0.37) / n;
    m.vertices.push_back(radius * Vec3(std::cos(a), std::sin(a), 0));
  }
  for (int k = 0; k < n; ++k) m.triangles.push_back({0u, std::uint32_t(1 + k), std::uint32_t(1 + (k + 1) % n)});
  return m;
}

// An open cone of `n` triangles, its apex at (0, 0, -depth), its rim of `radius` at z = height.
Mesh cone(int n, double depth, double height, double radius) {
  Mesh m;
  m.vertices.push_back(Vec3(0, 0, -depth));
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * (k + 0.11) / n;
    m.vertices.push_back(Vec3(radius * std::cos(a), radius * std::sin(a), height));
  }
  for (int k = 0; k < n; ++k) m.triangles.push_back({0u, std::uint32_t(1 + k), std::uint32_t(1 + (k + 1) % n)});
  return m;
}

std::vector<Object> fan_and_cone() {
  std::vector<Object> objects(2);
  objects[0].name = "fan";
  objects[0].mesh = fan(256, 1.0);
  objects[1].name = "cone";
  objects[1].mesh = cone(384, 0.02, 1.0, 0.5);
  return objects;
}

struct Run {
  FrameResult frame;
  Score score;
};

Run run(const std::vector<Object>& objects, const DetectOptions& opt, Resolve resolve, bool batch,
        bool filter = false) {
  gl::GlOptions o;
  o.resolve = resolve;
  o.batch = batch;
  o.gpu_filter = filter;  // off: every overlapping couple, as the host resolve lists them
  test_pipeline().set_gl_options(o);
  Run r;
  r.frame = test_pipeline().detect(objects, opt);
  test_pipeline().set_gl_options(gl::GlOptions{});
  REQUIRE(r.frame.pairs.size() == 1);
  r.score = score_contacts(exact_colliding_pairs(objects[0].mesh, objects[1].mesh), r.frame.pairs[0].colliding);
  return r;
}

// Stacks of `n` parallel squares per object, A's flat, B's tilted through them: every sample
// of the middle of the view meets 2n fragments (point sampling's deep texels).
std::vector<Object> stacks(int n) {
  std::vector<Object> objects(2);
  for (int o = 0; o < 2; ++o) {
    objects[o].name = o ? "tilted" : "flat";
    for (int k = 0; k < n; ++k) {
      const double z = 0.05 * k + (o ? 0.025 : 0.0), tilt = o ? 0.2 : 0.0;
      const auto first = std::uint32_t(objects[o].mesh.vertices.size());
      for (const auto& [x, y] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}})
        objects[o].mesh.vertices.push_back(Vec3(x, y, z + tilt * x));
      objects[o].mesh.triangles.push_back({first, first + 1, first + 2});
      objects[o].mesh.triangles.push_back({first, first + 2, first + 3});
    }
  }
  return objects;
}

// The GPU resolve against the host's on `objects`: the same PCS and layers, nothing missed
// (conservative), and the deep texels said (split, or the views resolved on the host).
void check_deep(const std::vector<Object>& objects, DetectOptions opt) {
  opt.stage = Stage::image;
  for (const int views : {1, 3})
    for (const bool batch : {true, false}) {
      opt.views = views;
      const Run host = run(objects, opt, Resolve::host, batch);
      const Run gpu = run(objects, opt, Resolve::gpu, batch);
      INFO((opt.conservative ? "conservative" : "point sampling")
           << ", " << views << " views, " << (batch ? "batched" : "one view at a time"));
      INFO("host " << host.score.found << " of " << host.score.exact << ", GPU " << gpu.score.found);
      CHECK(host.score.exact > 0);
      CHECK(gpu.frame.pairs[0].pcs == host.frame.pairs[0].pcs);
      CHECK(gpu.frame.pairs[0].layers == host.frame.pairs[0].layers);
      CHECK(gpu.score.found == host.score.found);
      if (opt.conservative) {
        CHECK(host.frame.pairs[0].layers > PEELCD_GPU_RESOLVE_DEPTH);  // every fragment a layer
        CHECK(gpu.score.missed == 0);
      }
      CHECK(host.frame.gl_deep_texels + host.frame.views_host_resolved == 0);  // nothing to say on the host
      // Conservative views resolved on the GPU are batched, one view alone included.
      if (opt.conservative && batch) {
        CHECK(gpu.frame.gl_deep_texels > 0);  // split over invocations, on the GPU
        CHECK(gpu.frame.views_host_resolved == 0);
        // The certified filter in both programs (a texel's own and the deep rows'): the same
        // contacts, the PCS among the unfiltered ones.
        const Run filtered = run(objects, opt, Resolve::gpu, batch, true);
        CHECK(filtered.score.missed == 0);
        CHECK(filtered.score.found == gpu.score.found);
        const auto& all = gpu.frame.pairs[0].pcs;
        std::size_t outside = 0;
        for (const auto& p : filtered.frame.pairs[0].pcs) outside += !std::binary_search(all.begin(), all.end(), p);
        CHECK(outside == 0);
        CHECK(filtered.frame.pairs[0].pcs.size() <= all.size());
      } else {
        CHECK(gpu.frame.views_host_resolved > 0);  // resolved on the host, and said
      }
    }
}

}  // namespace

TEST_CASE("deep texels: a fan pierced by a cone's tip, every triangle in one texel", "[deep][conservative][batch]") {
  const std::vector<Object> objects = fan_and_cone();
  // The fan meets the cone near its tip: every fan triangle and every cone triangle collides.
  REQUIRE(exact_colliding_pairs(objects[0].mesh, objects[1].mesh).size() >= 640);
  DetectOptions opt;
  opt.resolution = 16;
  check_deep(objects, opt);
}

TEST_CASE("deep texels: two real meshes at a 1-texel tile", "[deep][conservative][batch]") {
  const std::vector<Object> objects = load_objects(load_scene(std::string(PEELCD_FIXTURES) + "/scenes/bunny_dragon.json"));
  DetectOptions opt;
  opt.resolution = 1;
  check_deep(objects, opt);
}

TEST_CASE("deep texels: point sampling through 80 stacked squares", "[deep][batch]") {
  DetectOptions opt;
  opt.conservative = false;
  opt.resolution = 16;
  check_deep(stacks(40), opt);
}
