// Conservative mode on the GL stage (shaders/conservative.*): no colliding pair is missed on any
// class of geometry at several resolutions, nor on random intersecting pairs; a view no
// k-buffer can hold falls back to the exact CPU path. Point sampling keeps ties in both peelers.
#include "../core/proximity_cases.h"
#include "../core/random_contacts.h"
#include "gl_fixture.h"
#include "peelcd/core/primitives.h"
#include "peelcd/eval/classes.h"
#include "peelcd/eval/scenes.h"
#include "peelcd/core/world/world.h"
#include "stride.h"  // PEELCD_TEST_STRIDE: the sanitizer stage runs every Nth case of the long sweeps

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>

using namespace peelcd;
using namespace peelcd::test;

TEST_CASE("conservative mode misses nothing on any class of geometry", "[conservative][classes]") {
  for (const GeometryClass& g : geometry_classes(10)) {
    for (const int res : {0, 16, 64}) {
      DetectOptions opt;
      opt.stage = Stage::image;  // the image stage is what this checks
      REQUIRE(opt.conservative);
      opt.resolution = res;
      const ClassRow r = measure_class(test_pipeline().detector(), g, "conservative", opt, 1);
      INFO(g.name << " at " << (res ? std::to_string(res) : std::string("the budget")) << ": " << r.found << " of "
                  << r.exact);
      CHECK(r.exact > 0);
      CHECK(r.missed == 0);
    }
  }
}

TEST_CASE("conservative mode with the GPU's selection misses nothing on any class of geometry", "[conservative][classes][batch]") {
  // Every object made rigid (its shape resident, moved by a pose): the batch's selection passes
  // and their contact-region round choose the triangles, on boxes, touching and coincident
  // surfaces as on the rest. The pose turns and moves the whole scene, so the selection works in
  // rotated frames; the world meshes the exact reference reads are the poses applied to the shapes.
  const Eigen::Affine3d pose(Eigen::Translation3d(Vec3(0.3, -0.2, 0.1)) * Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  for (const bool turned : {false, true})
    for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
      gl::GlOptions o;
      o.resolve = resolve;
      test_pipeline().set_gl_options(o);
      const std::vector<GeometryClass> classes = geometry_classes(10);
      for (std::size_t i = 0; i < classes.size(); ++i) {
        if (test::stride_skips(i)) continue;
        GeometryClass g = classes[i];
        for (Object& object : g.objects) {
          const Eigen::Affine3d p = turned ? pose : Eigen::Affine3d::Identity();
          Mesh shape = object.mesh;
          for (Vec3& v : shape.vertices) v = p.inverse() * v;
          for (std::size_t k = 0; k < shape.vertices.size(); ++k) object.mesh.vertices[k] = p * shape.vertices[k];
          object.rigid = RigidMotion{std::make_shared<const Mesh>(std::move(shape)), p};
        }
        DetectOptions opt;
        opt.stage = Stage::image;
        opt.views = 3;  // three views of the pair: a batch (one view alone, on the host resolve, is drawn on its own)
        const ClassRow r = measure_class(test_pipeline().detector(), g, "conservative", opt, 1);
        INFO(g.name << (turned ? ", turned" : "") << ", resolve " << to_string(resolve) << ": " << r.found << " of "
                    << r.exact);
        CHECK(r.exact > 0);
        CHECK(r.missed == 0);
        const FrameResult f = test_pipeline().detect(g.objects, opt);
        CHECK(f.gl_draws == 2);        // the batch's count and fill draws
        CHECK(f.gl_dispatches >= 3);  // the selection's three passes
      }
      test_pipeline().set_gl_options(gl::GlOptions{});
    }
}

TEST_CASE("conservative mode: the GPU resolve and the host resolve give the same PCS", "[conservative]") {
  const std::vector<GeometryClass> classes = geometry_classes(3);
  for (const GeometryClass& g : classes) {
    DetectOptions opt;
    opt.stage = Stage::image;  // the image stage is what this checks
    opt.resolution = 64;
    std::vector<FrameResult> runs;
    for (const Resolve r : {Resolve::host, Resolve::gpu}) {
      gl::GlOptions o;
      o.resolve = r;
      o.gpu_filter = false;  // every overlapping couple, as the host resolve lists them
      test_pipeline().set_gl_options(o);
      runs.push_back(test_pipeline().detect(g.objects, opt));
    }
    test_pipeline().set_gl_options(gl::GlOptions{});
    REQUIRE(runs[0].pairs.size() == runs[1].pairs.size());
    for (std::size_t i = 0; i < runs[0].pairs.size(); ++i) {
      INFO(g.name << " pair " << i);
      CHECK(runs[0].pairs[i].pcs == runs[1].pairs[i].pcs);
      CHECK(runs[0].pairs[i].layers == runs[1].pairs[i].layers);
    }
  }
}

TEST_CASE("random intersecting pairs are always found in conservative mode", "[conservative][property]") {
  const char* env = std::getenv("PEELCD_CONSERVATIVE_GL_CASES");
  const long cases = env ? std::atol(env) : 400;
  RandomContacts gen(7);
  FrameResult f;
  long found = 0;
  for (long i = 0; i < cases; ++i) {
    const RandomContact c = gen.next();
    test_pipeline().detector().detect(c.objects, c.options, f);
    const bool hit = f.pairs.size() == 1 && f.pairs[0].colliding.size() == 1;
    if (!hit) {
      INFO("case " << c.index << " (" << kFamilyNames[int(c.family)] << "), resolution " << c.options.resolution
                   << ", theta " << c.options.theta << " phi " << c.options.phi << " roll " << c.options.roll);
      CHECK(hit);
    }
    found += hit;
  }
  CHECK(found == cases);
}

namespace {
// 13 stacked quads of A and 13 of B, each of B's crossing its neighbours in A: at 1024^2 every
// texel of a view along z holds 26 fragments.
void stacked_quads(Mesh& a, Mesh& b) {
  for (int k = 0; k < 13; ++k) {
    const Mesh qa = make_grid(Vec3(-5, -5, 0.1 * k), Vec3(10, 0, 0), Vec3(0, 10, 0), 1, 1);
    const Mesh qb = make_grid(Vec3(-5, -5, 0.1 * k + 0.05 - 0.1), Vec3(10, 0, 0.2), Vec3(0, 10, 0), 1, 1);
    for (auto [m, q] : {std::pair<Mesh*, const Mesh*>{&a, &qa}, {&b, &qb}}) {
      const auto base = std::uint32_t(m->vertices.size());
      m->vertices.insert(m->vertices.end(), q->vertices.begin(), q->vertices.end());
      for (const Tri& t : q->triangles) m->triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
  }
}
}  // namespace

TEST_CASE("a conservative view no k-buffer can hold goes to the exact CPU path", "[conservative]") {
  // 27 stacked quads of two objects, each of B's crossing its neighbours in A, at 1024^2: every
  // texel holds 26 fragments; on llvmpipe (128 MiB storage blocks) that k-buffer does not fit.
  Mesh a, b;
  stacked_quads(a, b);
  DetectOptions opt;
  opt.stage = Stage::image;  // the image stage is what this checks
  opt.resolution = 1024;
  const FrameResult f = test_pipeline().detect({{"a", a, {}, {}}, {"b", b, {}, {}}}, opt);
  REQUIRE(f.pairs.size() == 1);
  if (test_pipeline().renderer().find("llvmpipe") != std::string::npos) CHECK(f.views_exhaustive == 1);
  const Score s = score(exact_colliding_pairs(a, b), f.pairs[0].colliding);
  CHECK(s.exact > 0);
  CHECK(s.missed == 0);
}

TEST_CASE("point sampling keeps ties in both peelers: touching and coincident surfaces", "[ties]") {
  const std::vector<GeometryClass> classes = geometry_classes(2);
  for (const char* name : {"touching boxes", "coincident copy"})
    for (const Peeler peeler : {Peeler::abuffer, Peeler::multipass}) {
      const auto g = std::find_if(classes.begin(), classes.end(), [&](const GeometryClass& c) { return c.name == name; });
      REQUIRE(g != classes.end());
      DetectOptions paper = paper_options();
      paper.theta = 31;
      paper.phi = 51;
      paper.roll = 30;
      paper.resolution = 128;
      const ClassRow r =
          with_peeler(peeler, [&] { return measure_class(test_pipeline().detector(), *g, "paper", paper, 1); });
      INFO(name << " (" << to_string(peeler) << "): " << r.found << " of " << r.exact);
      CHECK(r.found > 0);
    }
}

TEST_CASE("conservative views packed into one k-buffer and drawn together give each view's layers and PCS",
          "[conservative][batch]") {
  // A crowd frame: rigid balls (poses in the views buffer) in light contact, many ROIs.
  std::vector<Object> objects;
  make_crowd(60, 2)->frame(1, objects);
  DetectOptions opt;  // the default configuration, the image stage forced
  opt.stage = Stage::image;
  std::vector<CapturedView> batched, single;
  gl::GlOptions one_by_one;
  one_by_one.batch = false;
  gl::GlOptions host;
  host.resolve = Resolve::host;  // the batch is the host resolve's (the default on llvmpipe)
  host.gpu_select = false;       // the host's selection of triangles, as the one-view path draws
  test_pipeline().set_gl_options(host);
  test_pipeline().capture_layers(&batched);
  const FrameResult b = test_pipeline().detect(objects, opt);
  test_pipeline().capture_layers(nullptr);
  const FrameResult b_fast = test_pipeline().detect(objects, opt);  // no capture
  one_by_one.resolve = Resolve::host;
  test_pipeline().set_gl_options(one_by_one);
  test_pipeline().detect(objects, opt);  // the one-view path grows its k-buffer's slots once
  test_pipeline().capture_layers(&single);
  const FrameResult s = test_pipeline().detect(objects, opt);
  test_pipeline().capture_layers(nullptr);
  gl::GlOptions gpu;
  gpu.resolve = Resolve::gpu;  // the batch resolved by one dispatch (shaders/conservative_batch_resolve.comp)
  gpu.gpu_select = false;
  gpu.gpu_filter = false;  // every overlapping couple, as the host resolve lists them
  test_pipeline().set_gl_options(gpu);
  const FrameResult g = test_pipeline().detect(objects, opt);
  test_pipeline().set_gl_options(gl::GlOptions{});
  REQUIRE(b.rois_peeled > 8);
  CHECK(g.gl_passes == 2);
  CHECK(g.gl_dispatches >= 1);
  CHECK(s.gl_passes == s.rois_peeled);  // one draw per view
  CHECK(b.gl_passes == 2);              // the count and fill draws of the one packed k-buffer
  CHECK(b_fast.gl_passes == b.gl_passes);
  REQUIRE(batched.size() == single.size());
  for (std::size_t v = 0; v < single.size(); ++v) {
    INFO("view " << v << " of pair " << single[v].pair);
    CHECK(batched[v].pair == single[v].pair);
    CHECK(batched[v].pcs == single[v].pcs);
    CHECK(batched[v].layers == single[v].layers);
  }
  REQUIRE(b.pairs.size() == s.pairs.size());
  std::size_t contacts = 0;
  for (std::size_t i = 0; i < s.pairs.size(); ++i) {
    CHECK(b.pairs[i].colliding.size() == s.pairs[i].colliding.size());
    CHECK(b_fast.pairs[i].pcs == s.pairs[i].pcs);
    CHECK(g.pairs[i].pcs == s.pairs[i].pcs);
    CHECK(g.pairs[i].layers == s.pairs[i].layers);
    contacts += s.pairs[i].colliding.size();
  }
  CHECK(contacts > 0);
}

TEST_CASE("a batch of more than 256 blocks of texels: the GPU's prefix sum gives the host's PCS, and the certified filter keeps its contacts", "[conservative][batch]") {
  // The GPU resolve sums the counts on the GPU (shaders/prefix_sum.comp: blocks of 1,024 texels,
  // their sums scanned 256 at a time); the 400-ball pile's frame packs about 330,000 texels. A
  // wrong offset would put fragments in another texel's range: PCS and layers would differ.
  std::vector<Object> objects;
  make_crowd(400, 2)->frame(1, objects);
  DetectOptions opt;
  opt.stage = Stage::image;
  gl::GlOptions o;
  o.resolve = Resolve::host;
  o.gpu_filter = false;  // every overlapping couple, as the host resolve lists them
  test_pipeline().set_gl_options(o);
  const FrameResult host = test_pipeline().detect(objects, opt);
  o.resolve = Resolve::gpu;
  test_pipeline().set_gl_options(o);
  const FrameResult gpu = test_pipeline().detect(objects, opt);
  test_pipeline().set_gl_options(gl::GlOptions{});
  std::size_t texels = 0;
  for (const PairResult& p : host.pairs) texels += std::size_t(p.views_peeled) * std::size_t(p.resolution) * std::size_t(p.resolution);
  INFO(texels << " texels in " << host.rois_peeled << " views");
  REQUIRE(texels > 256 * 1024);
  CHECK(gpu.gl_draws == 2);
  REQUIRE(gpu.pairs.size() == host.pairs.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < host.pairs.size(); ++i)
    differing += gpu.pairs[i].pcs != host.pairs[i].pcs || gpu.pairs[i].layers != host.pairs[i].layers;
  CHECK(differing == 0);

  // The certified filter (GlOptions::gpu_filter, the default) on the same frame: couples whose
  // triangles are certainly apart stay on the GPU. The contacts are the unfiltered frame's, every
  // PCS is one of its PCS, and what reaches the host's exact test is near the colliding pairs
  // (docs/backends.md's target: at most twice; unfiltered, about ten times).
  o.gpu_filter = true;
  test_pipeline().set_gl_options(o);
  const FrameResult filtered = test_pipeline().detect(objects, opt);
  test_pipeline().set_gl_options(gl::GlOptions{});
  REQUIRE(filtered.pairs.size() == gpu.pairs.size());
  std::size_t pcs_all = 0, pcs_kept = 0, colliding = 0, contacts_differ = 0, outside = 0;
  for (std::size_t i = 0; i < gpu.pairs.size(); ++i) {
    const PairResult &a = gpu.pairs[i], &f = filtered.pairs[i];
    pcs_all += a.pcs.size();
    pcs_kept += f.pcs.size();
    colliding += a.colliding.size();
    contacts_differ += a.colliding.size() != f.colliding.size() ||
                       !std::equal(a.colliding.begin(), a.colliding.end(), f.colliding.begin(),
                                   [](const Contact& x, const Contact& y) { return x.tri_a == y.tri_a && x.tri_b == y.tri_b; });
    for (const IdPair& p : f.pcs) outside += !std::binary_search(a.pcs.begin(), a.pcs.end(), p);
  }
  INFO(pcs_all << " PCS unfiltered, " << pcs_kept << " filtered, " << colliding << " colliding pairs");
  REQUIRE(colliding > 1000);
  CHECK(contacts_differ == 0);
  CHECK(outside == 0);
  CHECK(pcs_kept <= 2 * colliding);
  CHECK(pcs_all > 2 * colliding);  // the frame is one where the filter has work
  // Counted: at least one texel couple for each pair it kept away from the host.
  CHECK(gpu.gl_couples_apart == 0);
  CHECK(filtered.gl_couples_apart >= pcs_all - pcs_kept);
}

TEST_CASE("point-sampled views packed into one k-buffer give each pair's layers and PCS", "[batch]") {
  // The single-pass peeler's views batched as the conservative ones are (shaders/peel.vert,
  // abuffer.frag and abuffer_resolve.comp with PEELCD_BATCH): with the host's selection of
  // triangles, every pair's PCS, layers and contacts are the one-view path's, on both resolves.
  std::vector<Object> objects;
  make_crowd(60, 2)->frame(1, objects);  // rigid balls, every fifth deforming (corners from the host)
  DetectOptions opt;
  opt.stage = Stage::image;
  opt.conservative = false;
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    INFO("resolve " << to_string(resolve));
    gl::GlOptions o;
    o.resolve = resolve;
    o.gpu_select = false;
    o.batch = false;
    test_pipeline().set_gl_options(o);
    test_pipeline().detect(objects, opt);  // the one-view path grows its k-buffer's slots once
    const FrameResult single = test_pipeline().detect(objects, opt);
    o.batch = true;
    test_pipeline().set_gl_options(o);
    const FrameResult batched = test_pipeline().detect(objects, opt);
    o.gpu_select = true;
    test_pipeline().set_gl_options(o);
    const FrameResult selected = test_pipeline().detect(objects, opt);
    test_pipeline().set_gl_options(gl::GlOptions{});
    REQUIRE(single.rois_peeled > 8);
    CHECK(single.gl_passes >= single.rois_peeled);  // at least one draw per view
    CHECK(batched.gl_passes == 2);                  // the count and fill draws of the packed k-buffer
    CHECK(batched.gl_draws == 2);
    CHECK(selected.gl_draws == 2);
    CHECK(selected.triangles_indexed > batched.triangles_indexed);  // the selection draws more
    REQUIRE(batched.pairs.size() == single.pairs.size());
    std::size_t contacts = 0, pcs = 0;
    for (std::size_t i = 0; i < single.pairs.size(); ++i) {
      INFO("pair " << i);
      CHECK(batched.pairs[i].pcs == single.pairs[i].pcs);
      CHECK(batched.pairs[i].layers == single.pairs[i].layers);
      CHECK(batched.pairs[i].colliding.size() == single.pairs[i].colliding.size());
      contacts += single.pairs[i].colliding.size();
      pcs += single.pairs[i].pcs.size();
    }
    CHECK(contacts > 0);
    CHECK(pcs > contacts);
  }
}

TEST_CASE("rigid triangles selected on the GPU: the same contacts as the host's selection", "[conservative][batch]") {
  // The selection pass keeps every triangle of a rigid shape that reaches a view's volume and its
  // contact region (the boxes of both objects' triangles there); the host keeps those its
  // grid-based contact-region culling keeps. Neither drops a triangle that touches the other
  // object: every pair's contacts are the same, and each of them is among the GPU-selected PCS.
  std::vector<Object> objects;
  make_crowd(60, 2)->frame(1, objects);
  DetectOptions opt;
  opt.stage = Stage::image;
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    INFO("resolve " << to_string(resolve));
    gl::GlOptions o;
    o.resolve = resolve;
    o.gpu_select = false;
    test_pipeline().set_gl_options(o);
    const FrameResult host = test_pipeline().detect(objects, opt);
    o.gpu_select = true;
    test_pipeline().set_gl_options(o);
    const FrameResult gpu = test_pipeline().detect(objects, opt);
    const FrameResult again = test_pipeline().detect(objects, opt);  // the shapes resident now
    test_pipeline().set_gl_options(gl::GlOptions{});
    REQUIRE(gpu.rois_peeled > 8);
    CHECK(gpu.gl_dispatches >= 1);  // the selection pass
    CHECK(gpu.triangles_uploaded == host.triangles_uploaded);  // a deforming object's, as before
    CHECK(gpu.triangles_indexed > 0);
    INFO("rigid triangles drawn: host's selection " << host.triangles_indexed << ", GPU's " << gpu.triangles_indexed);
    CHECK(again.shape_uploads == 0);
    REQUIRE(gpu.pairs.size() == host.pairs.size());
    std::size_t contacts = 0;
    for (std::size_t i = 0; i < host.pairs.size(); ++i) {
      const PairResult& h = host.pairs[i];
      const PairResult& g = gpu.pairs[i];
      INFO("pair " << i);
      CHECK(g.pcs == again.pairs[i].pcs);  // the same set each frame
      REQUIRE(g.colliding.size() == h.colliding.size());
      for (std::size_t c = 0; c < h.colliding.size(); ++c) {
        CHECK(g.colliding[c].tri_a == h.colliding[c].tri_a);
        CHECK(g.colliding[c].tri_b == h.colliding[c].tri_b);
        // Unique IDs: a PCS is a couple of triangles.
        CHECK(std::binary_search(g.pcs.begin(), g.pcs.end(), IdPair{g.colliding[c].tri_a, g.colliding[c].tri_b}));
      }
      contacts += h.colliding.size();
    }
    CHECK(contacts > 0);
  }
}

TEST_CASE("GPU selection: a shape new to a frame moves the resident ones, every view still reads its own", "[conservative][batch]") {
  // Frame 1 makes two shapes resident; frame 2 drops the first and brings a larger one, which
  // grows the resident buffer: the second shape moves. Its views, earlier in the batch than the
  // new shape's, must draw it from where it is now (the IDs would be another shape's otherwise).
  const auto pair_of = [](const std::shared_ptr<const Mesh>& shape, double x, std::vector<Object>& out) {
    for (int k = 0; k < 2; ++k) {
      Object o;
      o.name = "ball" + std::to_string(out.size());
      const Eigen::Affine3d pose(Eigen::Translation3d(Vec3(x + 1.5 * k, 0.02 * k, 0.0)) *
                                 Eigen::AngleAxisd(0.3 * k, Vec3(0.0, 0.6, 0.8)));
      o.mesh = *shape;
      for (Vec3& v : o.mesh.vertices) v = pose * v;
      o.rigid = RigidMotion{shape, pose};
      out.push_back(std::move(o));
    }
  };
  DetectOptions opt;
  opt.stage = Stage::image;
  for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
    INFO("resolve " << to_string(resolve));
    // Shapes new to the stage each time round.
    auto s1 = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 12, 18));
    auto s2 = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 14, 20));
    auto s3 = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 40, 60));
    std::vector<Object> first, second;
    pair_of(s1, 0.0, first);
    pair_of(s2, 10.0, first);
    pair_of(s2, 10.0, second);
    pair_of(s3, 20.0, second);
    gl::GlOptions o;
    o.resolve = resolve;
    test_pipeline().set_gl_options(o);
    test_pipeline().detect(first, opt);
    s1.reset();
    first.clear();  // the first shape is no longer held
    const FrameResult got = test_pipeline().detect(second, opt);
    o.gpu_select = false;
    test_pipeline().set_gl_options(o);
    const FrameResult expected = test_pipeline().detect(second, opt);
    test_pipeline().set_gl_options(gl::GlOptions{});
    REQUIRE(got.pairs.size() == expected.pairs.size());
    REQUIRE(got.pairs.size() == 2);
    for (std::size_t i = 0; i < got.pairs.size(); ++i) {
      CHECK(!got.pairs[i].colliding.empty());
      CHECK(got.pairs[i].colliding.size() == expected.pairs[i].colliding.size());
      for (const Contact& c : got.pairs[i].colliding)
        CHECK(std::binary_search(got.pairs[i].pcs.begin(), got.pairs[i].pcs.end(), IdPair{c.tri_a, c.tri_b}));
    }
  }
}

TEST_CASE("the World's image-routed pairs together in one batch or one at a time: the same contacts", "[conservative][batch][world]") {
  // A row of rigid balls, each overlapping the next: many pairs routed to the image stage.
  std::vector<std::shared_ptr<const Mesh>> balls;
  for (int i = 0; i < 12; ++i)
    balls.push_back(std::make_shared<const Mesh>(make_uv_sphere(Vec3(1.5 * i, 0.1 * (i % 3), 0.05 * i), 1.0, 12, 24)));
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> runs;
  for (const bool together : {true, false}) {
    World world(make_image_stage(test_backend()));
    world.batch_image_pairs(together);
    for (const auto& b : balls) world.add_rigid(b, Eigen::Affine3d::Identity());
    DetectOptions opt;
    opt.stage = Stage::image;
    const FrameResult& f = world.collide(opt);
    REQUIRE(f.pairs.size() == 11);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> all;
    for (const PairResult& p : f.pairs) {
      INFO((together ? "together" : "one at a time") << ", pair " << p.object_a << "-" << p.object_b);
      CHECK_FALSE(p.exact_stage);
      const std::vector<std::uint64_t> exact = exact_colliding_pairs(*balls[p.object_a], *balls[p.object_b]);
      CHECK(p.colliding.size() == exact.size());  // conservative: every contact, each exact
      for (const Contact& c : p.colliding) all.emplace_back(c.tri_a + 10000u * p.object_a, c.tri_b + 10000u * p.object_b);
    }
    if (together) CHECK(f.gl_draws == 2u);  // one batch: its count and fill draws
    else CHECK(f.gl_draws >= 22u);          // each pair's own frame
    runs.push_back(all);
  }
  CHECK(runs[0] == runs[1]);
}

namespace {
// A pair's contacts as sorted packed couples.
std::vector<std::uint64_t> couples_of(const PairResult& p) {
  std::vector<std::uint64_t> out;
  for (const Contact& c : p.colliding) out.push_back(pack_pair(c.tri_a, c.tri_b));
  std::sort(out.begin(), out.end());
  return out;
}
Mesh posed(const Mesh& shape, const Eigen::Affine3d& pose) {
  Mesh m = shape;
  for (Vec3& v : m.vertices) v = pose * v;
  return m;
}
}  // namespace

TEST_CASE("the World's batched image pairs: drawn from resident shapes and moving meshes, untraversed, exact", "[conservative][batch][world]") {
  // Rigid balls of three shapes, turned and scaled, in a row that overlaps, and one deforming
  // sheet across two of them whose vertices wave every frame (and whose triangles are replaced in
  // the last frame). Stage::image, batched: no pair is traversed (no node pair visited, no
  // candidate from a tree), no triangle is copied, the rigid shapes and the sheet's triangles are
  // uploaded once (the sheet's vertices each frame), and every contact is the exact reference's,
  // also with ring IDs (expanded by the ID maps) and after the poses and vertices move.
  const std::vector<std::shared_ptr<const Mesh>> shapes = {
      std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 12, 24)),
      std::make_shared<const Mesh>(make_uv_sphere(Vec3(0.1, 0, 0), 0.8, 16, 20)),
      std::make_shared<const Mesh>(make_box(Vec3(-0.9, -0.7, -0.6), Vec3(0.9, 0.7, 0.6)))};
  const auto pose_of = [](int i, double t) {
    Eigen::Affine3d p = Eigen::Affine3d::Identity();
    p.translate(Vec3(1.45 * i + 0.05 * t, 0.1 * (i % 3), 0.05 * i));
    p.rotate(Eigen::AngleAxisd(0.3 * i + t, Vec3(1, 2, 3).normalized()));
    p.scale(1.0 + 0.05 * (i % 2));
    return p;
  };
  const Mesh flat = make_grid(Vec3(2.2, -2, -2), Vec3(0, 4, 0), Vec3(0.3, 0, 4), 12, 12);
  const auto sheet_at = [&](int frame) {  // a wave across the sheet; frame 2: a finer sheet
    Mesh m = frame < 2 ? flat : make_grid(Vec3(2.3, -2, -2), Vec3(0, 4, 0), Vec3(0.2, 0, 4), 17, 15);
    for (Vec3& v : m.vertices) v.x() += 0.15 * std::sin(1.7 * v.y() + 0.9 * v.z() + frame);
    return m;
  };
  for (const Resolve resolve : {Resolve::automatic, Resolve::gpu})
  for (const IdMode ids : {IdMode::unique, IdMode::ring}) {
    gl::GlOptions go;
    go.resolve = resolve;
    World world(make_image_stage(test_backend(), go));
    world.batch_image_pairs(true);
    std::vector<BodyId> rigid;
    for (int i = 0; i < 10; ++i) rigid.push_back(world.add_rigid(shapes[i % 3], pose_of(i, 0.0)));
    const BodyId deforming = world.add_deforming(sheet_at(0));
    DetectOptions opt;
    opt.stage = Stage::image;
    opt.ids = ids;
    for (int frame = 0; frame < 3; ++frame) {
      INFO("resolve " << to_string(resolve) << ", ids " << to_string(ids) << ", frame " << frame);
      for (int i = 0; i < 10; ++i) world.set_pose(rigid[std::size_t(i)], pose_of(i, 0.2 * frame));
      const Mesh sheet = sheet_at(frame);
      if (frame == 2) world.set_mesh(deforming, sheet);
      else world.set_vertices(deforming, sheet.vertices);
      const FrameResult& f = world.collide(opt);
      std::size_t rigid_pairs = 0, touching = 0, mixed_touching = 0;
      for (const PairResult& p : f.pairs) {
        CHECK_FALSE(p.exact_stage);
        const bool mixed = p.object_a == deforming || p.object_b == deforming;
        const Mesh ma = p.object_a == deforming ? sheet : posed(*shapes[p.object_a % 3], pose_of(int(p.object_a), 0.2 * frame));
        const Mesh mb = p.object_b == deforming ? sheet : posed(*shapes[p.object_b % 3], pose_of(int(p.object_b), 0.2 * frame));
        INFO("pair " << p.object_a << "-" << p.object_b);
        CHECK(couples_of(p) == exact_colliding_pairs(ma, mb));
        // Peeled, or no node pair of their trees meets in the ROI (nothing to peel).
        CHECK((p.views_peeled >= 1 || (p.region.empty() && p.colliding.empty())));
        if (ids == IdMode::unique) CHECK(p.pcs_count >= p.colliding.size());  // (a ring ID stands for several)
        rigid_pairs += !mixed;
        touching += !mixed && !p.colliding.empty();
        mixed_touching += mixed && !p.colliding.empty();
      }
      CHECK(rigid_pairs >= 9);
      CHECK(touching >= 5);
      CHECK(mixed_touching >= 1);  // the sheet cuts a ball
      CHECK(world.stats().node_pairs == 0);  // no traversal
      CHECK(world.stats().candidates == 0);
      CHECK(f.triangles_uploaded == 0);  // nothing copied: every triangle selected from resident ones
      CHECK(f.triangles_indexed > 0);
      CHECK(f.geometry_bytes > 0);  // the sheet's vertices
      if (frame == 1) CHECK(f.shape_uploads == 0);
      if (frame == 2) CHECK(f.shape_uploads == 1);  // the sheet's new triangles
    }
  }
  // Without the deforming body no pair is traversed at all, and nothing is uploaded of a mesh
  // once the shapes are resident.
  World world(make_image_stage(test_backend()));
  world.batch_image_pairs(true);
  std::vector<BodyId> rigid;
  for (int i = 0; i < 10; ++i) rigid.push_back(world.add_rigid(shapes[i % 3], pose_of(i, 0.0)));
  DetectOptions opt;
  opt.stage = Stage::image;
  world.collide(opt);
  for (int i = 0; i < 10; ++i) world.set_pose(rigid[std::size_t(i)], pose_of(i, 0.3));
  const FrameResult& f = world.collide(opt);
  CHECK(world.stats().node_pairs == 0);
  CHECK(world.stats().candidates == 0);
  CHECK(f.geometry_bytes == 0);
  CHECK(f.triangles_uploaded == 0);
  CHECK(f.triangles_indexed > 0);
  CHECK(f.gl_draws == 2u);  // one batch
  for (const PairResult& p : f.pairs)
    CHECK(couples_of(p) == exact_colliding_pairs(posed(*shapes[p.object_a % 3], pose_of(int(p.object_a), 0.3)),
                                                 posed(*shapes[p.object_b % 3], pose_of(int(p.object_b), 0.3))));
}

TEST_CASE("the World's resident image route: small bodies in many pairs are copied without trees, every contact exact", "[conservative][batch][world]") {
  // A 3x3x2 block of small rigid balls, each overlapping its neighbours (4 pairs or more: copied
  // into world space each frame they move), turning every frame, Stage::image, batched: their
  // copies give exact boxes (pairs dropped as on the exact path) but no tree is made (none is
  // traversed); the contacts are the exact reference's and the pairs the exact path's.
  auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 0.62, 10, 18));
  const auto pose_of = [](int i, int frame) {
    Eigen::Affine3d p = Eigen::Affine3d::Identity();
    p.translate(Vec3(1.0 * (i % 3) + 0.013 * frame, 1.0 * ((i / 3) % 3), 1.0 * (i / 9)));
    p.rotate(Eigen::AngleAxisd(0.4 * i + 0.21 * frame, Vec3(1, 2, 3).normalized()));
    return p;
  };
  gl::GlOptions go;
  go.resolve = Resolve::gpu;
  World image(make_image_stage(test_backend(), go));
  image.batch_image_pairs(true);
  World exact;
  std::vector<BodyId> ids;
  for (int i = 0; i < 18; ++i) {
    ids.push_back(image.add_rigid(ball, pose_of(i, 0)));
    exact.add_rigid(ball, pose_of(i, 0));
  }
  DetectOptions io, eo;
  io.stage = Stage::image;
  eo.stage = Stage::exact;
  std::size_t touching = 0;
  for (int frame = 1; frame < 4; ++frame) {
    INFO("frame " << frame);
    for (int i = 0; i < 18; ++i) {
      image.set_pose(ids[std::size_t(i)], pose_of(i, frame));
      exact.set_pose(ids[std::size_t(i)], pose_of(i, frame));
    }
    const FrameResult& f = image.collide(io);
    const FrameResult& e = exact.collide(eo);
    CHECK(image.stats().node_pairs == 0);  // untraversed
    REQUIRE(f.pairs.size() == e.pairs.size());  // the copies' exact boxes drop the same pairs
    for (std::size_t k = 0; k < f.pairs.size(); ++k) {
      const PairResult& p = f.pairs[k];
      INFO("pair " << p.object_a << "-" << p.object_b);
      CHECK(p.object_a == e.pairs[k].object_a);
      CHECK(p.object_b == e.pairs[k].object_b);
      CHECK_FALSE(p.exact_stage);
      CHECK(couples_of(p) == couples_of(e.pairs[k]));
      CHECK(couples_of(p) ==
            exact_colliding_pairs(posed(*ball, pose_of(int(p.object_a), frame)), posed(*ball, pose_of(int(p.object_b), frame))));
      touching += !p.colliding.empty();
    }
  }
  CHECK(touching >= 60);
}

TEST_CASE("the World's resident image route under random poses, sheared and scaled: every contact", "[conservative][world]") {
  // Two rigid shapes under random affine poses (rotation, non-uniform scale, shear), Stage::image
  // batched: each frame's region (the trees' meeting node pairs) must hold every contact, which
  // the exact reference checks couple by couple.
  const auto a = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 20, 30));
  const auto b = std::make_shared<const Mesh>(make_box(Vec3(-0.8, -0.5, -0.3), Vec3(0.8, 0.5, 0.3)));
  World world(make_image_stage(test_backend()));
  world.batch_image_pairs(true);
  const BodyId ia = world.add_rigid(a, Eigen::Affine3d::Identity());
  const BodyId ib = world.add_rigid(b, Eigen::Affine3d::Identity());
  DetectOptions opt;
  opt.stage = Stage::image;
  std::uint32_t seed = 12345u;
  const auto next = [&] {  // in [-1, 1)
    seed = seed * 1664525u + 1013904223u;
    return double(seed >> 8) / double(1u << 23) - 1.0;
  };
  std::size_t meeting = 0;
  for (int frame = 0; frame < 16; ++frame) {
    Eigen::Affine3d pa = Eigen::Affine3d::Identity(), pb = Eigen::Affine3d::Identity();
    pa.linear() = Eigen::AngleAxisd(3 * next(), Vec3(next(), next(), 1).normalized()).toRotationMatrix() *
                  Vec3(1.0 + 0.3 * next(), 1.0 + 0.3 * next(), 1.0).asDiagonal();
    pb.translation() = 0.9 * Vec3(next(), next(), next());
    pb.linear() = Eigen::AngleAxisd(3 * next(), Vec3(1, next(), next()).normalized()).toRotationMatrix();
    pb.linear()(0, 1) += 0.3 * next();  // a shear
    world.set_pose(ia, pa);
    world.set_pose(ib, pb);
    const FrameResult& f = world.collide(opt);
    INFO("frame " << frame);
    const std::vector<std::uint64_t> exact = exact_colliding_pairs(posed(*a, pa), posed(*b, pb));
    meeting += !exact.empty();
    if (f.pairs.empty()) {
      CHECK(exact.empty());
      continue;
    }
    REQUIRE(f.pairs.size() == 1);
    CHECK(couples_of(f.pairs[0]) == exact);
  }
  CHECK(meeting >= 8);
}

TEST_CASE("the World's resident image route on touching and coincident rigid boxes: every contact", "[conservative][world]") {
  // Faces that touch exactly (a box and its copy moved by its width, turned by a quarter turn
  // about the shared face's normal) and a coincident copy: the trees' region is a flat box or the
  // whole box, and every touching couple must still be found.
  const auto box = std::make_shared<const Mesh>(make_box(Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, 0.5)));
  World world(make_image_stage(test_backend()));
  world.batch_image_pairs(true);
  Eigen::Affine3d touching = Eigen::Affine3d::Identity();
  touching.translate(Vec3(1.0, 0.25, 0.0));
  touching.rotate(Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Vec3::UnitX()));
  Eigen::Affine3d far = Eigen::Affine3d::Identity();
  far.translate(Vec3(10.0, 0.0, 0.0));
  const std::vector<Eigen::Affine3d> poses = {Eigen::Affine3d::Identity(), touching, Eigen::Affine3d::Identity(), far};
  for (const Eigen::Affine3d& p : poses) world.add_rigid(box, p);
  DetectOptions opt;
  opt.stage = Stage::image;
  const FrameResult& f = world.collide(opt);
  REQUIRE(f.pairs.size() == 3);  // 0-1 and 1-2 touch, 0-2 coincide; 3 is far
  std::size_t meeting = 0;
  for (const PairResult& p : f.pairs) {
    INFO("pair " << p.object_a << "-" << p.object_b);
    const std::vector<std::uint64_t> exact = exact_colliding_pairs(posed(*box, poses[p.object_a]), posed(*box, poses[p.object_b]));
    CHECK(couples_of(p) == exact);
    meeting += !exact.empty();
  }
  CHECK(meeting == 3);
}

TEST_CASE("the World's resident image route: a view no k-buffer holds is tested on the traversal's candidates", "[conservative][world]") {
  // The stacked quads of the exhaustive case above as two bodies (two rigid; then A deforming,
  // moved by set_vertices, its refit put off by the route), one view at 1024^2: on the host's
  // resolve on llvmpipe the view cannot be resolved; the pair, not traversed (Stage::image), is
  // traversed then (the deforming body refitted first) and its contacts are the exact reference's.
  Mesh a, b;
  stacked_quads(a, b);
  for (const bool deforming : {false, true}) {
    INFO((deforming ? "A deforming" : "both rigid"));
    World world(make_image_stage(test_backend()));
    world.batch_image_pairs(true);
    Mesh moved = a;
    if (deforming) {
      const BodyId ia = world.add_deforming(a);
      for (Vec3& v : moved.vertices) v += Vec3(0.3, -0.2, 0.01);
      world.set_vertices(ia, moved.vertices);
    } else {
      world.add_rigid(std::make_shared<const Mesh>(a), Eigen::Affine3d::Identity());
    }
    world.add_rigid(std::make_shared<const Mesh>(b), Eigen::Affine3d::Identity());
    DetectOptions opt;
    opt.stage = Stage::image;
    opt.resolution = 1024;
    const FrameResult& f = world.collide(opt);
    REQUIRE(f.pairs.size() == 1);
    if (world.stage().renderer().find("llvmpipe") != std::string::npos) {  // resolved on the host there
      CHECK(f.views_exhaustive == 1);
      CHECK(f.pairs[0].candidates > 0);  // the tree's
    }
    CHECK(couples_of(f.pairs[0]) == exact_colliding_pairs(moved, b));
    CHECK(!f.pairs[0].colliding.empty());
  }
}

TEST_CASE("the World's resident image route: a large pair's PCS shared by the lanes' tasks, every contact exact", "[conservative][world]") {
  // Two bodies of 34k triangles between them or more (a large pair: one task a lane for the exact
  // tests of its PCS), on 3 threads, rigid and then one deforming: the contacts are the exact
  // path's; and the stacked quads of the case above with a large sphere far from them in A
  // (the pair large, its view still one no k-buffer holds on llvmpipe): traversed once from the
  // roots, the lanes' other tasks left empty, the contacts the exact reference's.
  const Mesh big = make_uv_sphere(Vec3::Zero(), 1.0, 110, 120);
  auto shape = std::make_shared<const Mesh>(big);
  for (const bool deforming : {false, true}) {
    INFO((deforming ? "A deforming" : "both rigid"));
    gl::GlOptions go;
    go.resolve = Resolve::gpu;
    World world(make_image_stage(test_backend(), go));
    world.batch_image_pairs(true);
    World exact;
    const Eigen::Affine3d at(Eigen::Translation3d(1.2, 0.31, 0.17) * Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    if (deforming) {
      Mesh m = big;
      for (Vec3& v : m.vertices) v = Vec3(v.x() * 1.1, v.y(), v.z() + 0.05 * std::sin(5.0 * v.x()));
      world.add_deforming(m);
      exact.add_deforming(m);
    } else {
      world.add_rigid(shape, Eigen::Affine3d::Identity());
      exact.add_rigid(shape, Eigen::Affine3d::Identity());
    }
    world.add_rigid(shape, at);
    exact.add_rigid(shape, at);
    DetectOptions opt, eo;
    opt.stage = Stage::image;
    opt.threads = 3;
    eo.stage = Stage::exact;
    const FrameResult& f = world.collide(opt);
    const FrameResult& e = exact.collide(eo);
    REQUIRE(f.pairs.size() == 1);
    REQUIRE(e.pairs.size() == 1);
    CHECK_FALSE(f.pairs[0].exact_stage);
    CHECK(world.stats().node_pairs == 0);
    CHECK(f.pairs[0].colliding.size() > 100);
    CHECK(couples_of(f.pairs[0]) == couples_of(e.pairs[0]));
  }
  Mesh a, b;
  stacked_quads(a, b);
  const Mesh far = make_uv_sphere(Vec3(40, 0, 0), 1.0, 110, 160);
  const auto base = std::uint32_t(a.vertices.size());
  a.vertices.insert(a.vertices.end(), far.vertices.begin(), far.vertices.end());
  for (const Tri& t : far.triangles) a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  REQUIRE(a.triangles.size() + b.triangles.size() >= 32768);
  World world(make_image_stage(test_backend()));
  world.batch_image_pairs(true);
  world.add_rigid(std::make_shared<const Mesh>(a), Eigen::Affine3d::Identity());
  world.add_rigid(std::make_shared<const Mesh>(b), Eigen::Affine3d::Identity());
  DetectOptions opt;
  opt.stage = Stage::image;
  opt.resolution = 1024;
  opt.threads = 3;
  const FrameResult& f = world.collide(opt);
  REQUIRE(f.pairs.size() == 1);
  if (world.stage().renderer().find("llvmpipe") != std::string::npos) CHECK(f.views_exhaustive == 1);
  CHECK(couples_of(f.pairs[0]) == exact_colliding_pairs(a, b));
  CHECK(!f.pairs[0].colliding.empty());
}

TEST_CASE("the World's resident image route puts a deforming body's refit off, and later frames see its vertices", "[conservative][world]") {
  // A waving sheet through a rigid ball, Stage::image batched: the route draws the sheet from its
  // loaded vertices and box without refitting its tree; a later frame on the exact path, a
  // partial move (move_vertices), a self pair and World::tree() each get the tree refitted over
  // the current vertices, and every frame's contacts are the exact reference's.
  const auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, 16, 32));
  const Mesh flat = make_grid(Vec3(-2, -2, 0.0), Vec3(4, 0, 0), Vec3(0, 4, 0), 24, 24);
  const auto wave = [&](int frame) {
    std::vector<Vec3> v = flat.vertices;
    for (Vec3& p : v) p.z() += 0.2 * std::sin(1.3 * p.x() + 0.7 * p.y() + frame) + 0.15 * frame;
    return v;
  };
  World world(make_image_stage(test_backend()));
  world.batch_image_pairs(true);
  const BodyId sheet = world.add_deforming(flat);
  const BodyId rigid = world.add_rigid(ball, Eigen::Affine3d::Identity());
  Mesh current = flat;
  const auto check_frame = [&](const DetectOptions& opt) {
    const FrameResult& f = world.collide(opt);
    std::size_t found = 0;
    for (const PairResult& p : f.pairs) {
      if (p.object_a != p.object_b) {
        CHECK(couples_of(p) == exact_colliding_pairs(current, *ball));
        found += p.colliding.size();
      }
    }
    return found;
  };
  DetectOptions image;
  image.stage = Stage::image;
  DetectOptions exact;
  exact.stage = Stage::exact;
  std::size_t found = 0;
  for (int frame = 0; frame < 6; ++frame) {
    INFO("frame " << frame);
    current.vertices = wave(frame);
    world.set_vertices(sheet, current.vertices);
    const std::size_t refits = world.stats().full_refits;
    if (frame == 2) {  // the exact path: the tree refitted over this frame's vertices
      found += check_frame(exact);
      CHECK(world.stats().full_refits == refits + 1);
      continue;
    }
    if (frame == 3) {  // a few vertices moved after the load: the loaded box is no longer theirs
      std::vector<std::uint32_t> moved_ids = {0u, 1u, 2u};
      std::vector<Vec3> to = {current.vertices[0] + Vec3(0, 0, 0.5), current.vertices[1], current.vertices[2]};
      current.vertices[0] = to[0];
      world.move_vertices(sheet, moved_ids, to);
    }
    if (frame == 4) world.set_self(sheet, true);  // a self pair needs the tree
    if (frame == 5) world.set_self(sheet, false);
    found += check_frame(image);
    if (frame == 0 || frame == 1 || frame == 5) CHECK(world.stats().full_refits == refits);  // put off
    else CHECK(world.stats().full_refits == refits + 1);
  }
  CHECK(found > 0);
  // World::tree() refits what was put off: its box is the current vertices'.
  const Aabb box = world.tree(sheet).box();
  const Aabb want = bounds(current);
  CHECK(box.lo == want.lo);
  CHECK(box.hi == want.hi);
  (void)rigid;
}

TEST_CASE("the World times its routes under Stage::automatic: both timed, every frame exact", "[conservative][world]") {
  // A waving sheet across a row of rigid balls, the resident route batched, Stage::automatic
  // with the routes timed (World::time_routes(true): on a software renderer they are not by
  // default): the first six frames compare the routed path and the image route (an untimed
  // frame and two timed each), later frames run the choice; every frame's contacts are the
  // exact reference's whichever route ran it. Unset on a software renderer, or false: never
  // the image route under Stage::automatic (the router's models send these pairs to the exact
  // path there).
  const auto ball = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 0.6, 12, 24));
  const Mesh flat = make_grid(Vec3(-0.5, -1.5, -1.5), Vec3(0, 3, 0), Vec3(0, 0, 3), 12, 12);
  const auto pose_of = [](int i, int frame) {
    Eigen::Affine3d p = Eigen::Affine3d::Identity();
    p.translate(Vec3(0.02 * frame, 1.0 * i - 1.0, 0.1 * i));
    p.rotate(Eigen::AngleAxisd(0.2 * frame + i, Vec3(1, 2, 3).normalized()));
    return p;
  };
  const auto sheet_at = [&](int frame) {
    Mesh m = flat;
    for (Vec3& v : m.vertices) v.x() += 0.1 * std::sin(1.7 * v.y() + 0.9 * v.z() + frame);
    return m;
  };
  for (const int setting : {1, 0, -1}) {  // time_routes(true), (false), unset
    INFO("time_routes " << setting);
    gl::GlOptions go;
    go.resolve = Resolve::gpu;  // the production path, also where GL runs on the CPU
    World world(make_image_stage(test_backend(), go));
    world.batch_image_pairs(true);
    if (setting >= 0) world.time_routes(setting == 1);
    std::vector<BodyId> balls;
    for (int i = 0; i < 3; ++i) balls.push_back(world.add_rigid(ball, pose_of(i, 0)));
    const BodyId sheet = world.add_deforming(flat);
    DetectOptions opt;  // Stage::automatic
    const int frames = setting == 1 ? 12 : 4;
    std::size_t found = 0;
    for (int frame = 0; frame < frames; ++frame) {
      INFO("frame " << frame);
      for (int i = 0; i < 3; ++i) world.set_pose(balls[std::size_t(i)], pose_of(i, frame));
      const Mesh current = sheet_at(frame);
      world.set_vertices(sheet, current.vertices);
      const bool comparing = world.comparing_routes();
      const std::size_t image_frames = world.stats().image_route_frames;
      const FrameResult& f = world.collide(opt);
      const bool image = world.stats().image_route_frames > image_frames;
      CHECK(world.stats().route_comparing == comparing);
      if (setting == 1 && frame < 6) {
        CHECK(comparing);
        CHECK(image == (frame >= 3));  // three frames routed, then three on the image route
      }
      if (setting != 1) CHECK_FALSE(image);
      for (const PairResult& p : f.pairs) {
        const Mesh ma = p.object_a == sheet ? current : posed(*ball, pose_of(int(p.object_a), frame));
        const Mesh mb = p.object_b == sheet ? current : posed(*ball, pose_of(int(p.object_b), frame));
        INFO("pair " << p.object_a << "-" << p.object_b << (image ? ", image route" : ", routed"));
        CHECK(couples_of(p) == exact_colliding_pairs(ma, mb));
        if (image) CHECK_FALSE(p.exact_stage);
        found += p.colliding.size();
      }
    }
    CHECK(found > 0);
    if (setting == 1) {
      CHECK_FALSE(world.comparing_routes());  // a choice after the comparison
      CHECK(world.stats().image_route_frames >= 3);
    } else {
      CHECK(world.stats().image_route_frames == 0);
    }
  }
}

TEST_CASE("conservative mode serves proximity: no pair within the margin missed, one view and batched", "[conservative][proximity]") {
  // Triangles grown by half the margin (PeelJob::grow) in the geometry shader, the batch's view
  // records and the GPU's selection: one view drawn alone, three batched with the host's and the
  // GPU's resolve, and the objects made rigid (the GPU selects their triangles).
  const std::vector<GeometryClass> scenes = test::proximity_scenes();
  std::size_t within = 0;
  for (const bool rigid : {false, true})
    for (const Resolve resolve : {Resolve::host, Resolve::gpu}) {
      gl::GlOptions o;
      o.resolve = resolve;
      test_pipeline().set_gl_options(o);
      for (std::size_t i = 0; i < scenes.size(); ++i) {
        if (test::stride_skips(i)) continue;
        GeometryClass g = scenes[i];
        if (rigid)
          for (Object& object : g.objects)
            object.rigid = RigidMotion{std::make_shared<const Mesh>(object.mesh), Eigen::Affine3d::Identity()};
        for (const double rel : {1e-3, 2e-2})
          for (const int views : {1, 3}) {
            DetectOptions opt;
            opt.stage = Stage::image;
            opt.views = views;
            opt.margin = rel * test::scene_size(g);
            INFO((rigid ? "rigid, " : "deforming, ") << "resolve " << to_string(resolve) << ", " << views << " views");
            within += test::check_near(test_pipeline().detector(), g, opt);
          }
      }
      test_pipeline().set_gl_options(gl::GlOptions{});
    }
  CHECK(within > 1000 / test::stride());
}

TEST_CASE("coverage by compute: the rasterizer's layers and PCS bit for bit, one view and batched", "[conservative][coverage]") {
  // GlOptions::coverage compute (shaders/conservative_cover.comp) against the rasterizer
  // (shaders/conservative.{vert,geom,frag}): every view's layers (captured on the host resolve),
  // PCS and contacts, on a crowd of rigid balls (poses in the views buffer; the GPU selection
  // appends to the entries the compute pass reads), the geometry classes posed, and proximity
  // (triangles grown by the margin); the one-view path (its deforming objects' corners and its
  // rigid shapes' indices) with both resolves, the batch with the host's selection and resolve,
  // and the batch with the GPU's selection and resolve (the certified filter off: every
  // overlapping couple); the compute pass's texels walked by each triangle's invocation or
  // shared among its workgroup.
  struct Case {
    std::string name;
    std::vector<Object> objects;
    DetectOptions opt;
  };
  std::vector<Case> cases;
  {
    Case c{"crowd", {}, {}};
    make_crowd(60, 2)->frame(1, c.objects);
    cases.push_back(c);
  }
  const Eigen::Affine3d pose(Eigen::Translation3d(Vec3(0.3, -0.2, 0.1)) * Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  for (GeometryClass g : geometry_classes(3)) {
    Case c{g.name, g.objects, {}};
    c.opt.views = 3;
    cases.push_back(c);
    for (Object& object : g.objects) {  // the same class, rigid and turned
      Mesh shape = object.mesh;
      for (Vec3& v : shape.vertices) v = pose.inverse() * v;
      object.rigid = RigidMotion{std::make_shared<const Mesh>(std::move(shape)), pose};
    }
    cases.push_back(Case{g.name + ", rigid", g.objects, c.opt});
  }
  for (const GeometryClass& g : test::proximity_scenes()) {
    Case c{g.name + ", margin", g.objects, {}};
    c.opt.margin = 2e-2 * test::scene_size(g);
    cases.push_back(c);
  }
  std::size_t views = 0, contacts = 0, case_index = 0;
  for (int path = 0; path < 4; ++path)
    for (const Case& c : cases) {
      const std::size_t index = case_index++;
      if (test::stride_skips(index)) continue;
      std::vector<CapturedView> captured[2];
      FrameResult frames[2];
      for (const Coverage coverage : {Coverage::raster, Coverage::compute}) {
        gl::GlOptions o;
        o.coverage = coverage;
        // The compute pass's texels: every triangle's shared among its workgroup, the large
        // triangles' only, or each walked by its triangle's invocation (the default on a
        // software renderer), in turn over the cases (every third kept under a stride of 3).
        const int shares[] = {0, 16, -1};
        o.cover_share_texels = shares[(index / 3) % 3];
        o.batch = path >= 2;
        o.resolve = path == 1 || path == 3 ? Resolve::gpu : Resolve::host;
        o.gpu_select = path == 3;
        o.gpu_filter = false;
        test_pipeline().set_gl_options(o);
        DetectOptions opt = c.opt;
        opt.stage = Stage::image;
        const int k = coverage == Coverage::compute;
        if (path != 3) test_pipeline().capture_layers(&captured[k]);
        frames[k] = test_pipeline().detect(c.objects, opt);
        test_pipeline().capture_layers(nullptr);
        if (coverage == Coverage::compute && frames[k].rois_peeled > 0) {
          CHECK(frames[k].gl_draws == 0);  // no conservative view was rasterized
          CHECK(frames[k].gl_dispatches > 0);
        }
      }
      test_pipeline().set_gl_options(gl::GlOptions{});
      const char* paths[] = {"one view, host", "one view, GPU", "batched, host", "batched, GPU"};
      INFO(c.name << ", path " << paths[path]);
      REQUIRE(captured[0].size() == captured[1].size());
      for (std::size_t v = 0; v < captured[0].size(); ++v) {
        INFO("view " << v << " of pair " << captured[0][v].pair);
        CHECK(captured[1][v].layers == captured[0][v].layers);
        CHECK(captured[1][v].pcs == captured[0][v].pcs);
        ++views;
      }
      REQUIRE(frames[0].pairs.size() == frames[1].pairs.size());
      for (std::size_t i = 0; i < frames[0].pairs.size(); ++i) {
        INFO("pair " << i);
        CHECK(frames[1].pairs[i].pcs == frames[0].pairs[i].pcs);
        CHECK(frames[1].pairs[i].layers == frames[0].pairs[i].layers);
        CHECK(frames[1].pairs[i].colliding.size() == frames[0].pairs[i].colliding.size());
        contacts += frames[0].pairs[i].colliding.size();
      }
    }
  CHECK(views > 50 / test::stride());
  CHECK(contacts > 0);
}

TEST_CASE("coverage by compute: views whose triangles span more texels than a software renderer loops over", "[conservative][coverage]") {
  // At 512^2 texels a view, a box's face spans tens of thousands of texels: more than one shader
  // invocation of llvmpipe (or lavapipe under zink) may loop over (65,535 iterations of all its
  // loops together), which ended the walk early and lost contacts. There such views rasterize
  // (gl/stage_impl.h, compute_coverage()); on a GPU they are covered by compute. Either way
  // every contact is the exact reference's, on the one-view path and in the batch, with every
  // share threshold.
  std::size_t checked = 0;
  for (const GeometryClass& g : geometry_classes(3)) {
    if (g.name != "crossing boxes" && g.name != "touching boxes") continue;
    for (const int share : {0, 16, -1})
      for (const bool batch : {false, true}) {
        gl::GlOptions o;
        o.coverage = Coverage::compute;
        o.cover_share_texels = share;
        o.batch = batch;
        test_pipeline().set_gl_options(o);
        DetectOptions opt;
        opt.stage = Stage::image;
        opt.resolution = 512;
        const ClassRow r = measure_class(test_pipeline().detector(), g, "conservative", opt, 1);
        INFO(g.name << ", share " << share << (batch ? ", batched" : ", one view") << ": " << r.found << " of "
                    << r.exact);
        CHECK(r.exact > 0);
        CHECK(r.missed == 0);
        ++checked;
      }
  }
  test_pipeline().set_gl_options(gl::GlOptions{});
  CHECK(checked == 12);
}
