// Conservative mode on the CPU image stage: no colliding pair is missed, on every class of
// geometry of peelcd/eval/classes.h at several resolutions, and on random intersecting pairs
// (the property docs/accuracy.md proves). The GL stages run the same checks in
// tests/gl/test_conservative.cpp.
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/eval/classes.h"
#include "random_contacts.h"

#include <catch2/catch.hpp>
#include "fixtures.h"

#include <cstdlib>

using namespace peelcd;
using namespace peelcd::test;

namespace {

using test::cpu_detector;

long env_count(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v ? std::atol(v) : fallback;
}

}  // namespace

TEST_CASE("conservative mode misses nothing on any class of geometry (CPU stage)", "[conservative][classes]") {
  for (const GeometryClass& g : geometry_classes(10)) {
    for (const int res : {0, 16, 64}) {  // 0: the default budget, shared by need
      DetectOptions opt;  // the default: conservative
      opt.stage = Stage::image;  // the image stage is what this checks
      REQUIRE(opt.conservative);
      opt.resolution = res;
      const ClassRow r = measure_class(cpu_detector(), g, "conservative", opt, 1);
      INFO(g.name << " at " << (res ? std::to_string(res) : std::string("the budget")) << ": " << r.found << " of "
                  << r.exact);
      CHECK(r.exact > 0);  // every class has contacts (the scene is what it claims)
      CHECK(r.missed == 0);
    }
  }
}

TEST_CASE("the crowded grid shares the budget by need", "[conservative][classes]") {
  const std::vector<GeometryClass> classes = geometry_classes(12);  // 144 spheres
  const GeometryClass& grid = classes.back();
  REQUIRE(grid.objects.size() == 144);
  FrameResult f;
  DetectOptions image;
  image.stage = Stage::image;
  cpu_detector().detect(grid.objects, image, f);
  long texels = 0;
  for (const PairResult& p : f.pairs) texels += long(p.resolution) * p.resolution;
  CHECK(texels <= 512L * 512L);  // the budget holds
  const ClassRow r = measure_class(cpu_detector(), grid, "default", image, 1);
  CHECK(r.exact > 1000);
  CHECK(r.missed == 0);
}

TEST_CASE("random intersecting pairs are always found in conservative mode (CPU stage)", "[conservative][property]") {
  // PEELCD_CONSERVATIVE_CASES raises the count (the soak target runs a million).
  const long cases = env_count("PEELCD_CONSERVATIVE_CASES", 3000);
  RandomContacts gen(20261123);
  FrameResult f;
  long found = 0;
  for (long i = 0; i < cases; ++i) {
    const RandomContact c = gen.next();
    cpu_detector().detect(c.objects, c.options, f);
    const bool hit = f.pairs.size() == 1 && f.pairs[0].colliding.size() == 1;
    if (!hit) {
      if (!f.pairs.empty())
        std::printf("miss %d: pairs %zu pcs %zu cand %zu res %d cull %s drawn %zu+%zu rigid %d%d ext %g\n", c.index,
                    f.pairs.size(), f.pairs[0].pcs_count, f.pairs[0].candidates, f.pairs[0].resolution,
                    to_string(c.options.cull), f.pairs[0].triangles_drawn_a, f.pairs[0].triangles_drawn_b,
                    bool(c.objects[0].rigid), bool(c.objects[1].rigid), f.pairs[0].roi.extent().maxCoeff());
      INFO("case " << c.index << " (" << kFamilyNames[int(c.family)] << "), resolution " << c.options.resolution
                   << ", theta " << c.options.theta << " phi " << c.options.phi << " roll " << c.options.roll);
      CHECK(hit);
    }
    found += hit;
  }
  CHECK(found == cases);
}

TEST_CASE("point sampling keeps ties: touching and coincident surfaces give PCS in the paper's mode", "[ties]") {
  const std::vector<GeometryClass> classes = geometry_classes(2);
  for (const char* name : {"touching boxes", "coincident copy"}) {
    const auto g = std::find_if(classes.begin(), classes.end(), [&](const GeometryClass& c) { return c.name == name; });
    REQUIRE(g != classes.end());
    DetectOptions paper = paper_options();
    paper.theta = 31;  // a frame where the faces are not edge-on
    paper.phi = 51;
    paper.roll = 30;
    const ClassRow r = measure_class(cpu_detector(), *g, "paper", paper, 1);
    INFO(name << ": " << r.found << " of " << r.exact);
    CHECK(r.found > 0);
  }
}
