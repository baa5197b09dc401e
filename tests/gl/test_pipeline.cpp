#include "peelcd/core/image/cull.h"
#include "peelcd/core/primitives.h"
#include "gl_fixture.h"

#include <catch2/catch.hpp>

using namespace peelcd;
using namespace peelcd::test;

namespace {

std::vector<Object> two(const Mesh& a, const Mesh& b) { return {{"a", a, {}, {}}, {"b", b, {}, {}}}; }

// Runs the pipeline and the CPU model of the image stage on the same ROI and options.
struct Run {
  PairResult gpu;
  CpuPeelResult cpu;
  Score score;
  double texel = 0;
  std::size_t missed_longer_than_a_texel = 0;  // misses an image-space method must not have
  std::size_t pcs_differences = 0;             // |GPU PCS symmetric-difference CPU model PCS|
};

// One view (the CPU model peels one), whatever the options say.
Run run(const Mesh& a, const Mesh& b, DetectOptions opt, Peeler peeler = Peeler::abuffer) {
  opt.views = 1;
  const FrameResult f = with_peeler(peeler, [&] { return test_pipeline().detect(two(a, b), opt); });
  REQUIRE(f.pairs.size() == 1);
  Run r;
  r.gpu = f.pairs[0];
  const RoiView view = make_padded_roi_view(r.gpu.region, bounds(a), bounds(b), view_frame(opt.theta, opt.phi), r.gpu.resolution);
  if (opt.cull == Cull::contact) {  // the model casts against the same triangles
    ContactCull cull;
    cull_to_contact_region(a, b, r.gpu.roi, cull);
    REQUIRE(cull.box.lo == r.gpu.region.lo);
    REQUIRE(cull.box.hi == r.gpu.region.hi);
    r.cpu = cpu_peel(a, b, view, opt.ids, r.gpu.epsilon, r.gpu.a_first, opt.peel, opt.slope, &cull.kept_a, &cull.kept_b);
  } else {
    r.cpu = cpu_peel(a, b, view, opt.ids, r.gpu.epsilon, r.gpu.a_first, opt.peel, opt.slope);
  }
  const auto exact = exact_colliding_pairs(a, b);
  r.score = score(exact, r.gpu.colliding);
  r.texel = view.texel();
  for (std::uint64_t e : exact) {
    const bool found = std::any_of(r.gpu.colliding.begin(), r.gpu.colliding.end(),
                                   [&](const Contact& c) { return pack_pair(c.tri_a, c.tri_b) == e; });
    const auto [p, q] = intersection_segment(corners(a, pair_a(e)), corners(b, pair_b(e)));
    if (!found && (p - q).norm() > r.texel) ++r.missed_longer_than_a_texel;
  }
  std::vector<IdPair> diff;
  std::set_symmetric_difference(r.gpu.pcs.begin(), r.gpu.pcs.end(), r.cpu.pcs.begin(), r.cpu.pcs.end(),
                                std::back_inserter(diff));
  r.pcs_differences = diff.size();
  return r;
}

}  // namespace

// See tests/core/test_cpu_peel.cpp for the picture: B pokes through A's x = 1 face; every ray
// through the ROI meets exactly two surfaces.
TEST_CASE("two axis-aligned boxes crossing", "[gl]") {
  const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = make_box(Vec3(0.5, 0.25, 0.25), Vec3(1.5, 0.75, 0.75));
  DetectOptions opt = point_sampling();
  opt.theta = 30;
  opt.phi = 20;
  opt.resolution = 128;
  opt.ids = IdMode::unique;
  opt.peel = PeelMode::full;
  opt.slope = 1.0;
  opt.cull = Cull::box;  // the whole overlap box, as the paper peels it

  SECTION("full peeling: entry and exit layers, PCS on the rim, every contact longer than a texel found") {
    const Peeler peeler = GENERATE(Peeler::multipass, Peeler::abuffer);
    INFO("peeler " << to_string(peeler));
    const Run r = run(a, b, opt, peeler);
    // Two surfaces per ray inside the ROI, and near the rim a third: B's side just beyond A's
    // face, in the ROI's padding (core/image/view.h, kRoiPadTexels).
    CHECK(r.gpu.layers == 3);
    // Multi-pass: the layers and the empty pass that ends the ROI; A-buffer: one draw.
    CHECK(r.gpu.passes == (peeler == Peeler::multipass ? 4 : 1));
    CHECK(r.gpu.pcs == r.cpu.pcs);
    for (const IdPair& p : r.gpu.pcs) {
      CHECK((p.a == 10 || p.a == 11));  // A's x = 1 face (core/primitives.cpp)
      CHECK(p.b < 8);                   // B's y and z faces
    }
    // B's 4 side faces (8 triangles) meet A's x = 1 face (2 triangles, diagonal y + z = 1) in
    // 12 pairs, 4 of them touching at one point only (where B's rim meets A's diagonal).
    CHECK(r.score.exact == 12);
    CHECK(r.score.false_contacts == 0);
    CHECK(r.missed_longer_than_a_texel == 0);
    CHECK(r.score.missed <= 4);
  }
  SECTION("contact culling keeps the two crossing faces and finds the same contacts in a smaller box") {
    const Peeler peeler = GENERATE(Peeler::multipass, Peeler::abuffer);
    INFO("peeler " << to_string(peeler));
    const Run whole = run(a, b, opt, peeler);
    opt.cull = Cull::contact;
    const Run r = run(a, b, opt, peeler);
    // In the ROI: A's x = 1 face (2 triangles), B's 4 side faces (8) and B's x = 0.5 face (2),
    // which lies inside A, far from A's surface: dropped.
    CHECK(r.gpu.triangles_in_roi_a == 2);
    CHECK(r.gpu.triangles_in_roi_b == 10);
    CHECK(r.gpu.triangles_drawn_a == 2);
    CHECK(r.gpu.triangles_drawn_b == 8);
    CHECK((r.gpu.region.extent().array() <= r.gpu.roi.extent().array()).all());
    CHECK(r.gpu.region.extent().prod() < r.gpu.roi.extent().prod());
    CHECK(r.gpu.pcs == r.cpu.pcs);
    CHECK(r.score.exact == 12);
    CHECK(r.score.false_contacts == 0);
    CHECK(r.missed_longer_than_a_texel == 0);
    CHECK(r.score.found >= whole.score.found);
  }
  SECTION("alternate peeling starts with A, the farther object, and misses what lies in front of it") {
    opt.peel = PeelMode::alternate;
    const Run r = run(a, b, opt);
    CHECK(r.gpu.a_first);
    CHECK(r.gpu.layers == r.cpu.layers);
    CHECK(r.gpu.pcs == r.cpu.pcs);
    CHECK(r.score.false_contacts == 0);
    CHECK(r.score.found < r.score.exact);
  }
}

TEST_CASE("a tilted plane through a sphere", "[gl]") {
  const Mesh sphere = make_uv_sphere(Vec3(0, 0, 0), 1.0, 24, 48);
  // Open grid through the sphere, tilted so its box is not flat: z = 0.1 + 0.2 x.
  const Mesh plane = make_grid(Vec3(-1.5, -1.5, -0.2), Vec3(3, 0, 0.6), Vec3(0, 3, 0), 12, 12);
  DetectOptions opt = point_sampling();
  opt.theta = 20;
  opt.phi = 50;
  opt.resolution = 256;
  for (Cull cull : {Cull::box, Cull::contact})
  for (PeelMode mode : {PeelMode::full, PeelMode::alternate}) {
    opt.peel = mode;
    opt.cull = cull;
    const Run r = run(sphere, plane, opt);
    INFO(to_string(mode) << ", cull " << to_string(cull) << ": found " << r.score.found << " of " << r.score.exact);
    // The sphere's front cap, the plane, the back cap: 3 surfaces on most rays.
    if (mode == PeelMode::full) CHECK(r.gpu.layers == 3);
    CHECK(r.gpu.layers == r.cpu.layers);
    // GL owns a texel centre on a shared edge to one triangle (the CPU model to both), and
    // compares float depths (the CPU model doubles): a few PCS may differ, never more than 2%.
    CHECK(r.pcs_differences <= r.gpu.pcs.size() / 50);
    CHECK(r.score.exact > 0);
    CHECK(r.score.false_contacts == 0);
    if (mode == PeelMode::full) CHECK(r.missed_longer_than_a_texel == 0);
  }
}

TEST_CASE("an open quad through a closed mesh", "[gl]") {
  const Mesh ball = make_uv_sphere(Vec3(0.2, 0.1, 0.0), 0.8, 16, 32);
  Mesh quad;  // two triangles, x from -2 to 2, slanted in y-z
  quad.vertices = {Vec3(-2, -2, -0.5), Vec3(2, -2, -0.5), Vec3(2, 2, 0.7), Vec3(-2, 2, 0.7)};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  DetectOptions opt = point_sampling();
  opt.theta = 75;
  opt.phi = -30;
  opt.resolution = 256;
  opt.peel = PeelMode::full;
  const Run r = run(ball, quad, opt);
  CHECK(r.gpu.triangles_drawn_b == 2);
  CHECK(r.gpu.layers == 3);  // front of the ball, the quad, back of the ball
  CHECK(r.pcs_differences <= r.gpu.pcs.size() / 50);  // see the sphere case for why
  CHECK(r.score.exact > 0);
  CHECK(r.score.false_contacts == 0);
  CHECK(r.missed_longer_than_a_texel == 0);
}

TEST_CASE("no overlapping boxes means no GL work at all", "[gl]") {
  const Mesh a = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  const Mesh b = make_box(Vec3(2, 0, 0), Vec3(3, 1, 1));
  const FrameResult f = test_pipeline().detect(two(a, b), point_sampling());
  CHECK(f.pairs.empty());
  CHECK(f.gl_passes == 0);
}

TEST_CASE("overlapping boxes without contact peel but report nothing", "[gl]") {
  // Two spheres whose boxes overlap at a corner while the surfaces stay apart (Fig. 2-b).
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 12, 24);
  const Mesh b = make_uv_sphere(Vec3(1.9, 1.9, 0), 1.0, 12, 24);
  DetectOptions opt = point_sampling();
  opt.resolution = 64;
  const FrameResult f = test_pipeline().detect(two(a, b), opt);
  REQUIRE(f.pairs.size() == 1);
  CHECK(f.pairs[0].colliding.empty());
  CHECK(exact_colliding_pairs(a, b).empty());
}

TEST_CASE("repeated frames reuse GL objects and give identical answers", "[gl]") {
  const Mesh a = make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32);
  const Mesh b = make_uv_sphere(Vec3(0.9, 0.4, 0.2), 0.7, 12, 24);
  DetectOptions opt = point_sampling();
  opt.theta = 10;
  opt.phi = 5;
  opt.edge_texels = 0;  // the whole budget, whatever the triangles' size
  const FrameResult f1 = test_pipeline().detect(two(a, b), opt);
  opt.resolution = 64;  // a different tile size in between reallocates the layers
  test_pipeline().detect(two(a, b), opt);
  opt.resolution = 0;
  const FrameResult f2 = test_pipeline().detect(two(a, b), opt);
  REQUIRE(f1.pairs.size() == 1);
  REQUIRE(f2.pairs.size() == 1);
  CHECK(f1.pairs[0].resolution == 512);  // one ROI takes the whole budget
  CHECK(f1.pairs[0].pcs == f2.pairs[0].pcs);
  CHECK(f1.pairs[0].colliding.size() == f2.pairs[0].colliding.size());
  CHECK_FALSE(f1.pairs[0].colliding.empty());
}

TEST_CASE("many ROIs share the texture budget", "[gl]") {
  std::vector<Object> objects;
  for (int i = 0; i < 6; ++i)  // a row of overlapping spheres: 5 ROIs
    objects.push_back({"s" + std::to_string(i), make_uv_sphere(Vec3(1.5 * i, 0, 0), 1.0, 8, 16), {}, {}});
  DetectOptions share = point_sampling();
  share.edge_texels = 0;  // every ROI takes its share of the budget
  const FrameResult f = test_pipeline().detect(objects, share);
  REQUIRE(f.pairs.size() == 5);
  // Five equal needs of the whole budget: each side scaled by 1/sqrt(5), to a multiple of 16.
  for (const PairResult& p : f.pairs) {
    CHECK(p.resolution == 224);
    CHECK(p.object_b == p.object_a + 1);
    CHECK_FALSE(p.colliding.empty());
  }
  // By default a ROI takes no more than 12 texels per median edge of its triangles: these
  // coarse spheres need far less than their share, and lose nothing by it.
  const FrameResult g = test_pipeline().detect(objects, point_sampling());
  REQUIRE(g.pairs.size() == 5);
  for (std::size_t i = 0; i < 5; ++i) {
    const PairResult& p = g.pairs[i];
    ContactCull cull;
    cull_to_contact_region(objects[p.object_a].mesh, objects[p.object_b].mesh, p.roi, cull);
    CHECK(p.resolution == edge_tile_resolution(512, cull.box, cull.median_edge, 12.0));  // all fit the budget
    CHECK(p.resolution < 224);
    const Score s = score(exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh), p.colliding);
    CHECK(s.false_contacts == 0);
    CHECK(s.found >= score(exact_colliding_pairs(objects[p.object_a].mesh, objects[p.object_b].mesh),
                           f.pairs[i].colliding).found);
    std::printf("spheres %zu-%zu: tile %d (equal share 224), found %zu of %zu\n", p.object_a, p.object_b, p.resolution,
                s.found, s.exact);
  }
}

TEST_CASE("impossible options are refused with a clear error", "[gl]") {
  const std::vector<Object> objs = two(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), make_box(Vec3(0.5, 0, 0), Vec3(2, 1, 1)));
  DetectOptions opt = point_sampling();
  opt.resolution = test_pipeline().max_resolution() + 1;
  CHECK_THROWS_WITH(test_pipeline().detect(objs, opt), Catch::Contains("GL_MAX_TEXTURE_SIZE"));
  opt = point_sampling();
  opt.epsilon = -1;
  CHECK_THROWS_AS(test_pipeline().detect(objs, opt), std::invalid_argument);
}

TEST_CASE("a rigid object's shape is uploaded once, then moved by its pose", "[gl]") {
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 0.7, 12, 24));
  const Mesh big = make_uv_sphere(Vec3(0, 0, 0), 1.0, 16, 32);
  DetectOptions opt = point_sampling();
  opt.theta = 10;
  opt.phi = 5;
  opt.resolution = 128;
  const auto frame = [&](const Vec3& at, bool rigid) {
    Eigen::Affine3d pose(Eigen::Translation3d(at) * Eigen::AngleAxisd(0.3, Vec3(0, 0, 1)));
    Mesh world;
    world.triangles = ball->triangles;
    for (const Vec3& v : ball->vertices) world.vertices.push_back(pose * v);
    std::vector<Object> objects = {{"big", big, {}, {}}, {"ball", world, {}, {}}};
    if (rigid) objects[1].rigid = RigidMotion{ball, pose};
    return std::make_pair(test_pipeline().detect(objects, opt), objects);
  };
  for (Peeler peeler : {Peeler::abuffer, Peeler::multipass}) {
    gl::GlOptions o;
    o.peeler = peeler;
    test_pipeline().set_gl_options(o);
    INFO("peeler " << to_string(peeler));
    // Several poses: the shape goes up once (or not at all, if an earlier section left it
    // cached); afterwards only indices, and the answers match the plain world-space path.
    std::size_t uploads = 0;
    for (const Vec3& at : {Vec3(0.9, 0.4, 0.2), Vec3(0.8, -0.5, 0.1), Vec3(-0.6, 0.6, -0.5)}) {
      const auto [rigid, objects] = frame(at, true);
      const auto [plain, unused] = frame(at, false);
      uploads += rigid.shape_uploads;
      REQUIRE(rigid.pairs.size() == 1);
      CHECK(rigid.triangles_indexed >= rigid.pairs[0].triangles_drawn_b);  // summed over the views
      CHECK(plain.triangles_uploaded > rigid.triangles_uploaded);
      CHECK(plain.triangles_indexed == 0);
      CHECK(plain.shape_uploads == 0);
      const Score s = score(exact_colliding_pairs(objects[0].mesh, objects[1].mesh), rigid.pairs[0].colliding);
      CHECK(s.false_contacts == 0);
      CHECK(s.found > 0);
      // Float rounding of the pose may move a texel's depth by an ulp: the same pairs up to 2%.
      const Score vs_plain = score(exact_colliding_pairs(objects[0].mesh, objects[1].mesh), plain.pairs[0].colliding);
      CHECK(std::abs(double(s.found) - double(vs_plain.found)) <= 0.02 * double(vs_plain.found) + 1);
    }
    CHECK(uploads <= 1);
  }
  test_pipeline().set_gl_options(gl::GlOptions{});
  // A new shape (the old one released) is uploaded again.
  ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3(0, 0, 0), 0.7, 10, 20));
  CHECK(frame(Vec3(0.9, 0.4, 0.2), true).first.shape_uploads == 1);
}

// 26 surfaces along every central ray, more than the single-pass peeler's k-buffer holds at
// first (16 fragments per texel): it must notice, grow, redraw, and end with multi-pass's layers
// and PCS, bit for bit.
// Two stacks of 13 quads each, interleaved: 26 surfaces along every central ray.
static std::pair<Mesh, Mesh> interleaved_stacks() {
  Mesh a, b;
  auto add_quad = [](Mesh& m, double z0, double tilt) {
    const Mesh q = make_grid(Vec3(-5, -5, z0 - 5 * tilt), Vec3(10, 0, 10 * tilt), Vec3(0, 10, 0), 1, 1);
    const auto base = std::uint32_t(m.vertices.size());
    m.vertices.insert(m.vertices.end(), q.vertices.begin(), q.vertices.end());
    for (const Tri& t : q.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  };
  for (int k = 0; k < 13; ++k) {
    add_quad(a, 0.1 * k, 0.0);
    add_quad(b, 0.1 * k + 0.05, 0.02);  // tilted: each crosses its neighbours in A
  }
  return {a, b};
}

// One oblique view of the stacks with full peeling: every surface is a layer.
static DetectOptions stacks_view(int resolution) {
  DetectOptions opt = point_sampling();
  opt.resolution = resolution;
  opt.views = 1;
  opt.theta = 20;
  opt.phi = 70;
  opt.peel = PeelMode::full;
  return opt;
}

TEST_CASE("texels deeper than the k-buffer: it grows and matches multi-pass", "[gl]") {
  const auto [a, b] = interleaved_stacks();
  gl::Pipeline fresh(test_context());  // its k-buffer starts at the default depth
  DetectOptions opt = stacks_view(64);
  std::vector<CapturedView> single, multi;
  fresh.capture_layers(&single);
  const FrameResult fs = fresh.detect(two(a, b), opt);
  fresh.set_gl_options({Peeler::multipass});
  fresh.capture_layers(&multi);
  const FrameResult fm = fresh.detect(two(a, b), opt);
  fresh.capture_layers(nullptr);
  REQUIRE(fs.pairs.size() == 1);
  REQUIRE(fm.pairs.size() == 1);
  CHECK(fs.pairs[0].layers == 26);
  CHECK(fs.pairs[0].layers == fm.pairs[0].layers);
  CHECK(fs.pairs[0].pcs == fm.pairs[0].pcs);
  CHECK(fs.pairs[0].colliding.size() == fm.pairs[0].colliding.size());
  CHECK_FALSE(fs.pairs[0].colliding.empty());
  REQUIRE(single.size() == 1);
  REQUIRE(multi.size() == 1);
  CHECK(single[0].layers == multi[0].layers);
  CHECK(single[0].pcs == multi[0].pcs);
}

// At 768^2, 26 fragments a texel need 235 MB of k-buffer: past llvmpipe's largest shader
// storage block (128 MB), so the view must go to multi-pass, with the same answer.
TEST_CASE("a k-buffer larger than a storage block falls back to multi-pass", "[gl]") {
  const auto [a, b] = interleaved_stacks();
  gl::Pipeline fresh(test_context());
  DetectOptions opt = stacks_view(768);
  const FrameResult fs = fresh.detect(two(a, b), opt);
  fresh.set_gl_options({Peeler::multipass});
  const FrameResult fm = fresh.detect(two(a, b), opt);
  REQUIRE(fs.pairs.size() == 1);
  REQUIRE(fm.pairs.size() == 1);
  if (fresh.renderer().find("llvmpipe") != std::string::npos) CHECK(fs.pairs[0].passes > 1);
  CHECK(fs.pairs[0].layers == fm.pairs[0].layers);
  CHECK(fs.pairs[0].pcs == fm.pairs[0].pcs);
  CHECK(fs.pairs[0].colliding.size() == fm.pairs[0].colliding.size());
  CHECK_FALSE(fs.pairs[0].colliding.empty());
}
