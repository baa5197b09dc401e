#include "peelcd/bench/suite.h"
#include "peelcd/core/clock.h"

#include "peelcd/bench/float_peers.h"
#include "peelcd/bench/floor.h"
#include "peelcd/bench/peers.h"
#include "peelcd/core/id_map.h"
#include "peelcd/core/reference.h"
#include "peelcd/core/world.h"
#include "peelcd/gl/gl_stage.h"
#include "peelcd/version.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace peelcd::bench {
namespace {

void add(Score& total, const Score& s) {
  total.exact += s.exact;
  total.found += s.found;
  total.missed += s.missed;
  total.false_contacts += s.false_contacts;
}

// The same for a peer, object pair by object pair (the peers' broad phases may list pairs in
// another order, or more of them).
Score score_peer(const PeerFrame& exact, const PeerFrame& peer) {
  Score total;
  static const std::vector<std::uint64_t> none;
  for (std::size_t i = 0; i < exact.objects.size(); ++i) {
    const auto it = std::lower_bound(peer.objects.begin(), peer.objects.end(), exact.objects[i]);
    const std::vector<std::uint64_t>& got =
        it != peer.objects.end() && *it == exact.objects[i] ? peer.per_pair[std::size_t(it - peer.objects.begin())] : none;
    std::vector<std::uint64_t> common;
    std::set_intersection(exact.per_pair[i].begin(), exact.per_pair[i].end(), got.begin(), got.end(),
                          std::back_inserter(common));
    total.exact += exact.per_pair[i].size();
    total.found += common.size();
    total.missed += exact.per_pair[i].size() - common.size();
    total.false_contacts += got.size() - common.size();
  }
  // Pairs the peer reported that the exact broad phase does not list: all false.
  for (std::size_t j = 0; j < peer.objects.size(); ++j)
    if (!std::binary_search(exact.objects.begin(), exact.objects.end(), peer.objects[j]))
      total.false_contacts += peer.per_pair[j].size();
  return total;
}

enum class Kind { world, frame, cgal, fcl_refit, fcl_rebuild, embree_refit, embree_rebuild, bullet, floor_box, floor_culled };

struct Row {
  std::string name, column;
  Kind kind = Kind::frame;
  DetectOptions opt;
  gl::GlOptions gl;
  std::unique_ptr<World> world;  // Kind::world: its bodies, kept from frame to frame
  std::vector<BodyId> bodies;
  FrameResult result;
  std::vector<double> ms, stage_ms;
  std::vector<std::vector<double>> phase_ms;
  Score score;
  bool peelcd() const { return kind == Kind::world || kind == Kind::frame; }
  bool floor() const { return kind == Kind::floor_box || kind == Kind::floor_culled; }
};

}  // namespace

Score score_frame(const FrameResult& r, const PeerFrame& exact) {
  Score total;
  static const std::vector<Contact> none;
  for (std::size_t i = 0; i < exact.objects.size(); ++i) {
    const std::vector<Contact>* found = &none;
    for (const PairResult& p : r.pairs)
      if (p.object_a == exact.objects[i].first && p.object_b == exact.objects[i].second) found = &p.colliding;
    add(total, score_contacts(exact.per_pair[i], *found));
  }
  return total;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

namespace {

bool keep_freed_memory() {
#if defined(__GLIBC__)
  return mallopt(M_MMAP_THRESHOLD, 1 << 30) == 1 && mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1;
#else
  return false;
#endif
}

}  // namespace

std::string run_suite(const Suite& suite) {
  auto* gl_stage = dynamic_cast<gl::GlImageStage*>(suite.stage.get());
  if (!gl_stage) throw std::invalid_argument("peelcd bench: the benchmark times GL stages (use osmesa or egl)");
  if (suite.res > 0 && suite.res > gl_stage->max_resolution())
    throw std::invalid_argument("peelcd bench: --res " + std::to_string(suite.res) + " is above GL_MAX_TEXTURE_SIZE");
  // Freed memory stays in the process: the methods take turns on every frame, and one that frees
  // gigabytes (the CGAL reference, FCL's cropped trees) would otherwise hand them back to the
  // kernel and make whichever method runs next pay for it (on this project's VMs that made the
  // next method's frame 2-3x slower: docs/performance.md, "Side by side"). Every method gets
  // the same allocator; the library itself never changes it.
  const bool heap_kept = suite.keep_freed_memory && keep_freed_memory();
  Detector detector(suite.stage);
  const unsigned threads = std::max(1u, suite.threads);
  const gl::GlOptions gl_base = gl_stage->options();

  std::vector<Row> rows;
  const auto row = [&](std::string name, std::string column, Kind kind, const DetectOptions& opt = {},
                       const gl::GlOptions& gl = {}) -> Row& {
    Row& r = rows.emplace_back();
    r.name = std::move(name);
    r.column = std::move(column);
    r.kind = kind;
    r.opt = opt;
    r.gl = gl;
    return r;
  };
  DetectOptions base;  // the default of detect: the router
  base.threads = threads;
  base.resolution = suite.res;
  gl::GlOptions gpu_resolve = gl_base;
  gpu_resolve.resolve = Resolve::gpu;
  gl::GlOptions multi = gl_base;
  multi.peeler = Peeler::multipass;
  DetectOptions image = base;
  image.stage = Stage::image;

  // peelcd's persistent bodies: the default a user with objects that persist gets.
  row("peelcd default (World, stage auto)", "default", Kind::world, base, gl_base);
  row("peelcd World, image stage", "W image", Kind::world, image, gl_base);
  // The frame API: every frame's world meshes, nothing kept but the GL stage's rigid shapes.
  row("peelcd frame API (stage auto)", "frame", Kind::frame, base, gl_base);
  DetectOptions exact = base;
  exact.stage = Stage::exact;
  if (!suite.short_rows) row("peelcd frame API, exact CPU path", "exact", Kind::frame, exact, gl_base);
  row("peelcd frame API, image stage", "image", Kind::frame, image, gl_base);
  DetectOptions point = image;  // the paper's image stage with this project's culling, views, slope
  point.conservative = false;
  point.ids = IdMode::ring;
  point.theta = point.phi = point.roll = 0.0;
  point.views = 3;
  if (!suite.short_rows) {
    DetectOptions box = image;
    box.cull = Cull::box;
    row("peelcd image stage, box culling", "box cull", Kind::frame, box, gl_base);
    row("peelcd image stage, GPU resolve", "gpu rslv", Kind::frame, image, gpu_resolve);
    DetectOptions half = image;  // half the tile side: the texels culling saves
    if (half.resolution > 0)
      half.resolution = std::max(16, half.resolution / 2);
    else
      half.budget = std::max(16, half.budget / 2);
    row("peelcd image stage, half resolution", "half res", Kind::frame, half, gl_base);
    if (image.resolution == 0) {  // the conservative stage's earlier tiles: 12 texels per median edge
      DetectOptions fine = image;
      fine.edge_texels = kPointEdgeTexels;
      row("peelcd image stage, 12 texels per edge", "12 tx/edge", Kind::frame, fine, gl_base);
    }
    // Point sampling: lossy, see the miss column.
    row("peelcd point sampling, 3 views", "point 3v", Kind::frame, point, gl_base);
    row("peelcd point sampling, multi-pass", "multipass", Kind::frame, point, multi);
    DetectOptions one = point;
    one.views = 1;
    row("peelcd point, 1 view, full peeling", "1v full", Kind::frame, one, gl_base);
    DetectOptions paper = one;  // the paper's pipeline: the whole overlap box, one view
    paper.peel = PeelMode::alternate;
    paper.ids = IdMode::paper;
    paper.slope = 0.0;
    paper.cull = Cull::box;
    if (suite.res == 0 && suite.phases == 1 && suite.scene.find(".json") != std::string::npos)
      paper.resolution = 256;  // the paper's 256^2 on one pair (its Fig. 8)
    row("peelcd paper config", "paper", Kind::frame, paper, gl_base);
    row("peelcd paper config, multi-pass", "paper mp", Kind::frame, paper, multi);
  }
  const std::size_t first_peer = rows.size();
  row("CGAL, cropped to the overlap box", "CGAL", Kind::cgal);
  row("FCL 0.7, deforming refit", "FCL refit", Kind::fcl_refit);
  row("FCL 0.7, deforming rebuilt cropped", "FCL build", Kind::fcl_rebuild);
  row("Embree 3 rtcCollide, refit", "Embree rf", Kind::embree_refit);
  row("Embree 3 rtcCollide, rebuilt low", "Embree lo", Kind::embree_rebuild);
  row("Bullet 3 GImpact, refit", "Bullet", Kind::bullet);
  // The floors: one bare draw of every triangle touching the overlap box (the paper's ROI), and
  // of the triangles contact culling keeps (what the image-stage configurations draw).
  DetectOptions floor1 = point, cfloor1 = point;
  floor1.views = cfloor1.views = 1;
  floor1.cull = Cull::box;
  cfloor1.cull = Cull::contact;
  cfloor1.edge_texels = edge_texels_of(image);  // the conservative image stage's tiles
  row("floor: 1 bare draw, overlap box", "floor", Kind::floor_box, floor1, gl_base);
  row("floor: 1 bare draw, culled", "cfloor", Kind::floor_culled, cfloor1, gl_base);
  const std::size_t cg = first_peer, fr = first_peer + 1, fb = first_peer + 2, fl = first_peer + 6, cfl = first_peer + 7;
  for (Row& r : rows) {
    r.phase_ms.assign(std::size_t(std::max(1, suite.phases)), {});
    if (r.kind == Kind::world) r.world = std::make_unique<World>(suite.stage);
  }
  FclPeer fcl_refit(FclPeer::Deforming::refit, threads);
  FclPeer fcl_rebuild(FclPeer::Deforming::rebuild, threads);
  EmbreePeer embree_refit(EmbreePeer::Update::refit, threads);
  EmbreePeer embree_rebuild(EmbreePeer::Update::rebuild_low, threads);
  BulletPeer bullet(threads);

  // One frame of one peelcd row: a World brought to the frame (timed with it: the update is
  // part of its frame, as FCL's refits are of FCL's), or the frame API.
  const auto run_peelcd = [&](Row& r, const std::vector<Object>& objects) {
    gl_stage->set_options(r.gl);
    if (r.kind == Kind::world) {
      const auto t0 = Clock::now();
      sync_bodies(*r.world, objects, r.bodies);
      r.world->collide(r.opt, r.result);
      r.result.timings.total = ms_since(t0);
    } else {
      detector.detect(objects, r.opt, r.result);
    }
  };

  std::string csv = "peelcd_version,frame,method,ms,nctp,found,false_contacts\n";
  std::vector<Object> objects;
  // One untimed pass over the frames first: shader compilation, rigid shapes' uploads, the trees
  // of rigid shapes and the growth of every buffer happen once, and would otherwise land on
  // whichever method meets them first. The timed pass is the steady state. (A scene file's
  // frames are all the same: one untimed frame.)
  const std::size_t warm = suite.phases > 1 || suite.frames <= 1 ? suite.frames : std::min<std::size_t>(suite.frames, 2);
  for (std::size_t f = 0; f < warm; ++f) {
    suite.frame(f, objects);
    for (Row& r : rows)
      if (r.peelcd()) run_peelcd(r, objects);
    fcl_refit.frame(objects);
    fcl_rebuild.frame(objects);
    embree_refit.frame(objects);
    embree_rebuild.frame(objects);
    bullet.frame(objects);
  }
  std::size_t rois = 0, rois_exact = 0, world_candidates = 0, triangles = 0;
  for (std::size_t f = 0; f < suite.frames; ++f) {
    suite.frame(f, objects);
    const int phase = suite.phase ? suite.phase(f) : 0;
    // Side by side on the same frame: the exact reference first (it is the CGAL peer).
    const PeerFrame ref = cgal_frame(objects, threads);
    for (std::size_t m = 0; m < rows.size(); ++m) {
      Row& r = rows[m];
      double ms = 0.0, stage_ms = 0.0;
      Score s;
      switch (r.kind) {
        case Kind::world:
        case Kind::frame:
          run_peelcd(r, objects);
          ms = r.result.timings.total;
          stage_ms = r.result.timings.gpu;
          s = score_frame(r.result, ref);
          break;
        case Kind::cgal:
          ms = ref.ms;
          s = Score{ref.pairs, ref.pairs, 0, 0};
          break;
        case Kind::fcl_refit:
        case Kind::fcl_rebuild:
        case Kind::embree_refit:
        case Kind::embree_rebuild:
        case Kind::bullet: {
          const PeerFrame p = r.kind == Kind::fcl_refit        ? fcl_refit.frame(objects)
                              : r.kind == Kind::fcl_rebuild    ? fcl_rebuild.frame(objects)
                              : r.kind == Kind::embree_refit   ? embree_refit.frame(objects)
                              : r.kind == Kind::embree_rebuild ? embree_rebuild.frame(objects)
                                                               : bullet.frame(objects);
          ms = p.ms;
          s = score_peer(ref, p);
          break;
        }
        case Kind::floor_box:
        case Kind::floor_culled:
          gl_stage->set_options(r.gl);
          ms = floor_ms(detector, *gl_stage, objects, r.opt);
          s = Score{ref.pairs, 0, ref.pairs, 0};
          break;
      }
      r.ms.push_back(ms);
      r.stage_ms.push_back(stage_ms);
      r.phase_ms[std::size_t(phase)].push_back(ms);
      add(r.score, s);
      char line[256];
      std::snprintf(line, sizeof line, "%s,%zu,\"%s\",%.4f,%zu,%zu,%zu\n", PEELCD_VERSION_STRING, f, r.name.c_str(), ms,
                    s.exact, s.found, s.false_contacts);
      csv += line;
    }
    const FrameResult& frame_api = rows[2].result;
    rois += frame_api.pairs.size();
    rois_exact += frame_api.rois_exact;
    for (const PairResult& p : rows[0].result.pairs) world_candidates += p.candidates;
    if (suite.progress) suite.progress(f + 1, suite.frames);
  }
  for (const Object& o : objects) triangles += o.mesh.triangles.size();

  std::vector<double> med(rows.size());
  for (std::size_t m = 0; m < rows.size(); ++m) med[m] = median(rows[m].ms);
  // The FCL ratio is against the faster of its two ways with deforming objects.
  const std::size_t fc = med[fr] <= med[fb] ? fr : fb;
  // The best peer: the fastest of CGAL, FCL, Embree and Bullet rows.
  std::size_t best = cg;
  for (std::size_t m = cg; m < fl; ++m)
    if (med[m] < med[best]) best = m;
  const int tile = suite.res ? suite.res : base.budget;
  std::printf("peelcd bench: %s, %zu frames, %zu objects, %zu triangles, %s, %s (%s), medians per frame after an untimed pass\n",
              suite.scene.c_str(), suite.frames, objects.size(), triangles,
              suite.res ? (std::to_string(tile) + "^2 per ROI").c_str()
                        : ("a " + std::to_string(tile) + "^2 budget shared by the ROIs").c_str(),
              suite.stage->backend().c_str(), suite.stage->renderer().c_str());
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("threads: %u for every method (CGAL, FCL: object pairs; peelcd: object pairs, the node pairs of one pair's "
              "trees (World), host resolve lanes); llvmpipe %s; freed memory %s\n",
              threads, lp ? (std::string("LP_NUM_THREADS=") + lp).c_str() : "its default (one per core)",
              heap_kept ? "kept in the process (mallopt)" : "returned as the allocator decides");
  std::printf("World: %.0f candidate couples per frame (mean, default row); frame API router: %zu of %zu ROIs to the "
              "exact CPU path over the timed frames\n",
              suite.frames ? double(world_candidates) / double(suite.frames) : 0.0, rois_exact, rois);
  std::printf("%-38s %10s %9s %8s %7s %8s %8s %8s %8s\n", "method", "median ms", "stage ms", "miss", "false", "x CGAL",
              "x FCL", "x best", "x floor");
  for (std::size_t m = 0; m < rows.size(); ++m) {
    const Row& r = rows[m];
    std::printf("%-38s %10.2f", r.name.c_str(), med[m]);
    if (r.peelcd())
      std::printf(" %9.2f", median(r.stage_ms));
    else
      std::printf(" %9s", "-");
    if (r.floor())
      std::printf(" %8s %7s", "-", "-");
    else
      std::printf(" %7.2f%% %7zu", 100.0 * r.score.miss_ratio(), r.score.false_contacts);
    if (m < cg) {
      const std::size_t floor = r.opt.cull == Cull::box ? fl : cfl;
      std::printf(" %8.2f %8.2f %8.2f %8.2f\n", med[m] / med[cg], med[m] / med[fc], med[m] / med[best],
                  med[floor] > 0 ? med[m] / med[floor] : 0.0);
    } else {
      std::printf("\n");
    }
  }
  std::printf("(miss / false: over all frames against the exact pairs; FCL's, Embree's and Bullet's triangle tests are not exact\n"
              " (Embree, Bullet: Moller's test in float); the floor finds nothing.\n"
              " stage ms: the image stage's GPU work, timed on the host to its end (0 on the exact path); the rest is host work.\n"
              " x CGAL: against the cropped CGAL peer; x FCL: against the faster FCL row (%s); x best: against the fastest\n"
              " peer row (%s); x floor: against one bare\n"
              " draw of the triangles the configuration would draw, one view. FCL trees kept: %zu (refit row), %zu (rebuilt\n"
              " row); refits %zu; cropped per-pair trees %zu and %zu, all frames. World rows: their bodies brought to each\n"
              " frame (poses; a deforming body's vertices and refit) inside the time.)\n",
              fc == fr ? "refit" : "rebuilt", rows[best].name.c_str(), fcl_refit.builds(), fcl_rebuild.builds(), fcl_refit.refits(),
              fcl_refit.pair_builds(), fcl_rebuild.pair_builds());
  if (suite.phases > 1) {
    std::printf("\nper phase, median ms:\n%-7s", "phase");
    for (const Row& r : rows) std::printf(" %9s", r.column.c_str());
    std::printf(" %9s %9s %9s\n", "dflt/CGAL", "dflt/FCL", "dflt/best");
    for (int p = 0; p < suite.phases; ++p) {
      std::printf("(%c)    ", char('a' + p));
      if (rows[0].phase_ms[std::size_t(p)].empty()) {  // fewer frames than phases
        std::printf(" no frames\n");
        continue;
      }
      std::vector<double> pm(rows.size());
      for (std::size_t m = 0; m < rows.size(); ++m) std::printf(" %9.2f", pm[m] = median(rows[m].phase_ms[std::size_t(p)]));
      const double best_peer = *std::min_element(pm.begin() + std::ptrdiff_t(cg), pm.begin() + std::ptrdiff_t(fl));
      std::printf(" %9.2f %9.2f %9.2f\n", pm[0] / pm[cg], pm[0] / std::min(pm[fr], pm[fb]), pm[0] / best_peer);
    }
  }
  return csv;
}

}  // namespace peelcd::bench
