#include "peelcd/bench/suite.h"
#include "peelcd/core/clock.h"

#include "peelcd/bench/float_peers.h"
#include "peelcd/bench/plain_peers.h"
#include "peelcd/bench/floor.h"
#include "peelcd/bench/peers.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/world/world.h"
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
// A World brought to the frame as the float peers bring theirs (float_peers.cpp): a deforming
// body whose triangle and vertex counts are unchanged keeps its topology (set_vertices); a
// rigid body gets its pose (and its shape when it changed). sync_bodies() compares the
// triangles themselves, which no peer pays for; the bench's scenes change a topology only with
// its counts (a wrong guess would show in the miss column).
void bring_world(World& world, const std::vector<Object>& objects, std::vector<BodyId>& bodies) {
  if (bodies.size() != objects.size()) {  // the first frame (or a mismatch, which it reports)
    sync_bodies(world, objects, bodies);
    return;
  }
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const Object& o = objects[i];
    const BodyId id = bodies[i];
    world.set_self(id, o.self);
    if (o.rigid) {
      if (&world.mesh(id) != o.rigid->shape.get()) world.set_shape(id, o.rigid->shape);
      world.set_pose(id, o.rigid->pose);
    } else if (o.mesh.triangles.size() == world.mesh(id).triangles.size() &&
               o.mesh.vertices.size() == world.mesh(id).vertices.size()) {
      world.set_vertices(id, o.mesh.vertices);
    } else {
      world.set_mesh(id, o.mesh);
    }
  }
}

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

enum class Kind { world, frame, cgal, peer, floor_box, floor_culled };

// Where one frame of a peelcd row went (the image-work table): host work (the frame less the
// host's GL waits), the GPU passes by timer queries, the bytes uploaded, the candidates the host
// tested exactly and the colliding pairs among them.
struct Split {
  double total = 0, wait = 0, raster = 0, compute = 0, transfer = 0;
  double select = 0, cover = 0;  // parts of compute: the batch's selection, the compute coverage
  double uploaded = 0, geometry = 0, candidates = 0, colliding = 0, rois_peeled = 0;
  double apart = 0;  // texel couples the GPU's certified filter dropped (FrameResult::gl_couples_apart)
  double boxes = 0, views = 0, stage = 0, readback = 0, exact = 0;  // the host's steps (Timings)
  std::size_t untimed = 0;  // passes whose timer query gave an impossible time (left out)
};

struct Row {
  std::string name, column;
  Kind kind = Kind::frame;
  DetectOptions opt;
  gl::GlOptions gl;
  std::unique_ptr<World> world;  // Kind::world: its bodies, kept from frame to frame
  Peer* peer = nullptr;          // Kind::peer: SuiteRun::peers_'s
  std::vector<BodyId> bodies;
  FrameResult result;
  std::vector<double> ms, stage_ms;
  std::vector<Split> split;
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

// The peers of the suite, one line each (`all`: the labelled variants too).
std::vector<std::unique_ptr<Peer>> make_peers(unsigned threads, bool all, bool audit) {
  std::vector<std::unique_ptr<Peer>> peers;
  peers.push_back(std::make_unique<FclPeer>(FclPeer::Deforming::refit, threads));
  peers.push_back(std::make_unique<FclPeer>(FclPeer::Deforming::rebuild, threads));
  peers.push_back(std::make_unique<EmbreePeer>(EmbreePeer::Update::refit, threads));
  peers.push_back(std::make_unique<EmbreePeer>(EmbreePeer::Update::rebuild_low, threads));
  // A variant, labelled: Embree's refit row with tri_tri_float() (a frame at a corner, scaled)
  // for Moller's published test; not a peer's default.
  if (all) peers.push_back(std::make_unique<EmbreePeer>(EmbreePeer::Update::refit, threads, TriangleTest::scaled));
  peers.push_back(std::make_unique<BulletPeer>(threads));
  // --audit: each library as a plain user writes it (bench/plain_embree.cpp, plain_bullet.cpp,
  // plain_fcl.cpp), against the rows above.
  if (audit) {
    for (const PlainPeer::Library l : {PlainPeer::Library::fcl, PlainPeer::Library::embree, PlainPeer::Library::bullet})
      peers.push_back(std::make_unique<PlainPeer>(l));
  }
  return peers;
}

Split split_of(const FrameResult& r) {
  Split s;
  s.total = r.timings.total;
  s.wait = r.timings.gl_wait;
  s.raster = r.timings.gpu_raster;
  s.compute = r.timings.gpu_compute;
  s.select = r.timings.gpu_select;
  s.cover = r.timings.gpu_cover;
  s.transfer = r.timings.gpu_transfer;
  s.uploaded = double(r.bytes_uploaded);
  s.geometry = double(r.geometry_bytes);
  s.rois_peeled = double(r.rois_peeled);
  s.apart = double(r.gl_couples_apart);
  s.untimed = r.timings.gpu_passes_untimed;
  s.boxes = r.timings.aabb;
  s.views = r.timings.upload;
  s.stage = r.timings.gpu;
  s.readback = r.timings.readback;
  s.exact = r.timings.cpu;
  for (const PairResult& p : r.pairs) {
    s.candidates += double(p.candidates);
    s.colliding += double(p.colliding.size());
  }
  return s;
}

bool keep_freed_memory() {
#if defined(__GLIBC__)
  return mallopt(M_MMAP_THRESHOLD, 1 << 30) == 1 && mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1;
#else
  return false;
#endif
}

}  // namespace

namespace {

// One run of the suite: its rows (peelcd's configurations, the peers, the floors), the peers'
// state, the frames timed side by side, the tables printed.
class SuiteRun {
 public:
  SuiteRun(const Suite& suite, gl::GlImageStage& gl_stage)
      : suite_(suite),
        gl_stage_(gl_stage),
        detector_(suite.stage),
        threads_(std::max(1u, suite.threads)),
        peers_(make_peers(threads_, !suite.short_rows, suite.audit)) {}

  std::string run(bool heap_kept) {
    add_rows();
    warm_up();
    csv_ = "peelcd_version,frame,method,ms,nctp,found,false_contacts\n";
    for (std::size_t f = 0; f < suite_.frames; ++f) time_frame(f);
    if (scaling_) scaling_pass();
    for (const Object& o : objects_) triangles_ += o.mesh.triangles.size();
    print_table(heap_kept);
    print_image_work();
    if (suite_.phases > 1) print_phases();
    return csv_;
  }

 private:
  const Suite& suite_;
  gl::GlImageStage& gl_stage_;
  Detector detector_;
  unsigned threads_;
  std::vector<std::unique_ptr<Peer>> peers_;
  std::vector<Row> rows_;
  DetectOptions base_;  // the default of detect: the router
  std::size_t cg_ = 0, fl_ = 0, cfl_ = 0;  // the CGAL row, the floor rows (the peers' between them)
  std::size_t scaling_ = 0;  // the default World row with Suite::scaling_threads (0: none)
  std::size_t pairs_ = 0;    // the default World row asking for pairs only
  std::vector<double> alone_ms_[2];  // scaling_pass(): the default row, the scaling row
  std::vector<double> modelled_;     // scaling_pass(): the lane model's frame / the frame, per frame
  std::vector<Object> objects_;
  std::string csv_;
  std::size_t rois_ = 0, rois_exact_ = 0, world_candidates_ = 0, triangles_ = 0;
  std::size_t world_image_frames_ = 0;  // the default row's timed frames on the image route (routes timed)

  Row& row(std::string name, std::string column, Kind kind, const DetectOptions& opt = {}, const gl::GlOptions& gl = {}) {
    Row& r = rows_.emplace_back();
    r.name = std::move(name);
    r.column = std::move(column);
    r.kind = kind;
    r.opt = opt;
    r.gl = gl;
    return r;
  }
  void add_rows();
  void add_image_rows(const DetectOptions& image, const DetectOptions& point, const gl::GlOptions& gl_base);
  void warm_up();
  void run_peelcd(Row& r);
  double time_row(Row& r, const PeerFrame& ref, Score& s, double& stage_ms);
  void time_frame(std::size_t f);
  void scaling_pass();
  void print_table(bool heap_kept) const;
  // The row with the least time of those `which` accepts (the CGAL row when none does).
  template <class Which>
  std::size_t fastest(const std::vector<double>& ms, Which which) const {
    std::size_t best = cg_;
    bool found = false;
    for (std::size_t m = 0; m < rows_.size(); ++m)
      if (which(rows_[m]) && (!found || ms[m] < ms[best])) best = m, found = true;
    return best;
  }
  void print_image_work() const;
  void print_audit(const std::vector<double>& med) const;
  void print_host_steps() const;
  void print_phases() const;
};

void SuiteRun::add_rows() {
  const gl::GlOptions gl_base = gl_stage_.options();
  base_.threads = threads_;
  base_.resolution = suite_.res;
  DetectOptions image = base_;
  image.stage = Stage::image;
  // peelcd's persistent bodies: the default a user with objects that persist gets.
  row("peelcd default (World, stage auto)", "default", Kind::world, base_, gl_base);
  row("peelcd World, image stage", "W image", Kind::world, image, gl_base);
  // The frame API: every frame's world meshes, nothing kept but the GL stage's rigid shapes.
  row("peelcd frame API (stage auto)", "frame", Kind::frame, base_, gl_base);
  DetectOptions exact = base_;
  exact.stage = Stage::exact;
  if (!suite_.short_rows) row("peelcd frame API, exact CPU path", "exact", Kind::frame, exact, gl_base);
  row("peelcd frame API, image stage", "image", Kind::frame, image, gl_base);
  DetectOptions point = image;  // the paper's image stage with this project's culling, views, slope
  point.conservative = false;
  point.ids = IdMode::ring;
  point.theta = point.phi = point.roll = 0.0;
  point.views = 3;
  if (!suite_.short_rows) add_image_rows(image, point, gl_base);
  cg_ = rows_.size();
  row("CGAL, cropped to the overlap box", "CGAL", Kind::cgal);
  for (const std::unique_ptr<Peer>& p : peers_) row(p->name(), p->column(), Kind::peer).peer = p.get();
  // The floors: one bare draw of every triangle touching the overlap box (the paper's ROI), and
  // of the triangles contact culling keeps (what the image-stage configurations draw).
  DetectOptions floor1 = point, cfloor1 = point;
  floor1.views = cfloor1.views = 1;
  floor1.cull = Cull::box;
  cfloor1.cull = Cull::contact;
  cfloor1.edge_texels = edge_texels_of(image);  // the conservative image stage's tiles
  fl_ = rows_.size();
  cfl_ = fl_ + 1;
  row("floor: 1 bare draw, overlap box", "floor", Kind::floor_box, floor1, gl_base);
  row("floor: 1 bare draw, culled", "cfloor", Kind::floor_culled, cfloor1, gl_base);
  // The default with the colliding pairs alone (no segment or kind: what the float peers return).
  DetectOptions pairs_only = base_;
  pairs_only.contacts = ContactDetail::pairs;
  pairs_ = rows_.size();
  row("peelcd World, pairs only (stage auto)", "pairs", Kind::world, pairs_only, gl_base);
  if (suite_.scaling_threads > 0) {  // last: the other rows keep their places
    DetectOptions scaled = base_;
    scaled.threads = suite_.scaling_threads;
    scaling_ = rows_.size();
    row("peelcd default, " + std::to_string(suite_.scaling_threads) + " threads", "dflt " + std::to_string(suite_.scaling_threads) + "t",
        Kind::world, scaled, gl_base);
  }
  for (Row& r : rows_) {
    r.phase_ms.assign(std::size_t(std::max(1, suite_.phases)), {});
    if (r.kind == Kind::world) {
      r.world = std::make_unique<World>(suite_.stage);
      if (suite_.time_routes) r.world->time_routes(suite_.time_routes);
    }
  }
}

// The image stage's variants (the full table): GPU resolve, half resolution, finer tiles, point
// sampling (lossy: see the miss column), the paper's configuration.
void SuiteRun::add_image_rows(const DetectOptions& image, const DetectOptions& point, const gl::GlOptions& gl_base) {
  gl::GlOptions gpu_resolve = gl_base;
  gpu_resolve.resolve = Resolve::gpu;
  gl::GlOptions multi = gl_base;
  multi.peeler = Peeler::multipass;
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
  if (image.resolution == 0) {  // the conservative stage at 12 texels per median edge
    DetectOptions fine = image;
    fine.edge_texels = kPointEdgeTexels;
    row("peelcd image stage, 12 texels per edge", "12 tx/edge", Kind::frame, fine, gl_base);
  }
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
  if (suite_.res == 0 && suite_.phases == 1 && suite_.scene.find(".json") != std::string::npos)
    paper.resolution = 256;  // the paper's 256^2 on one pair (its Fig. 8)
  row("peelcd paper config", "paper", Kind::frame, paper, gl_base);
  row("peelcd paper config, multi-pass", "paper mp", Kind::frame, paper, multi);
}

// One frame of one peelcd row: a World brought to the frame (timed with it: the update is part
// of its frame, as FCL's refits are of FCL's), or the frame API.
void SuiteRun::run_peelcd(Row& r) {
  gl_stage_.set_options(r.gl);
  if (r.kind == Kind::world) {
    const auto t0 = Clock::now();
    bring_world(*r.world, objects_, r.bodies);
    r.world->collide(r.opt, r.result);
    r.result.timings.total = ms_since(t0);
  } else {
    detector_.detect(objects_, r.opt, r.result);
  }
}

// One untimed pass over the frames first: shader compilation, rigid shapes' uploads, the trees
// of rigid shapes and the growth of every buffer happen once, and would otherwise land on
// whichever method meets them first. The timed pass is the steady state. (A scene file's frames
// are all the same: one untimed frame.)
void SuiteRun::warm_up() {
  const std::size_t warm = suite_.phases > 1 || suite_.frames <= 1 ? suite_.frames : std::min<std::size_t>(suite_.frames, 2);
  for (std::size_t f = 0; f < warm; ++f) {
    suite_.frame(f, objects_);
    for (Row& r : rows_)
      if (r.peelcd()) run_peelcd(r);
    for (const std::unique_ptr<Peer>& p : peers_) p->frame(objects_);
  }
  // A World that times its routes (Stage::automatic on a GPU: World::time_routes()) compares
  // them over its first frames: it runs the last warm frame again until it has chosen (at most
  // 16 frames), so that the timed pass is its choice's steady state, not its comparison.
  for (Row& r : rows_)
    if (r.kind == Kind::world && r.opt.stage == Stage::automatic)
      for (int extra = 0; extra < 16 && r.world->comparing_routes(); ++extra) run_peelcd(r);
}

// One row on the current frame: its time, its score against the exact pairs (`ref`, the CGAL
// peer's), the image stage's time (peelcd rows).
double SuiteRun::time_row(Row& r, const PeerFrame& ref, Score& s, double& stage_ms) {
  stage_ms = 0.0;
  switch (r.kind) {
    case Kind::world:
    case Kind::frame:
      run_peelcd(r);
      stage_ms = r.result.timings.gpu;
      s = score_frame(r.result, ref);
      return r.result.timings.total;
    case Kind::cgal:
      s = Score{ref.pairs, ref.pairs, 0, 0};
      return ref.ms;
    case Kind::peer: {
      const PeerFrame p = r.peer->frame(objects_);
      s = score_peer(ref, p);
      return p.ms;
    }
    case Kind::floor_box:
    case Kind::floor_culled:
      gl_stage_.set_options(r.gl);
      s = Score{ref.pairs, 0, ref.pairs, 0};
      return floor_ms(detector_, gl_stage_, objects_, r.opt);
  }
  return 0.0;
}

// Frame f, every row side by side on it: the exact reference first (it is the CGAL peer).
void SuiteRun::time_frame(std::size_t f) {
  suite_.frame(f, objects_);
  const int phase = suite_.phase ? suite_.phase(f) : 0;
  const PeerFrame ref = cgal_frame(objects_, threads_);
  for (Row& r : rows_) {
    Score s;
    double stage_ms = 0.0;
    const std::size_t image_frames = r.world ? r.world->stats().image_route_frames : 0;
    const double ms = time_row(r, ref, s, stage_ms);
    if (&r == &rows_[0] && r.world) world_image_frames_ += r.world->stats().image_route_frames - image_frames;
    r.ms.push_back(ms);
    r.stage_ms.push_back(stage_ms);
    if (r.peelcd()) r.split.push_back(split_of(r.result));
    r.phase_ms[std::size_t(phase)].push_back(ms);
    add(r.score, s);
    char line[256];
    std::snprintf(line, sizeof line, "%s,%zu,\"%s\",%.4f,%zu,%zu,%zu\n", PEELCD_VERSION_STRING, f, r.name.c_str(), ms,
                  s.exact, s.found, s.false_contacts);
    csv_ += line;
  }
  const FrameResult& frame_api = rows_[2].result;
  rois_ += frame_api.pairs.size();
  rois_exact_ += frame_api.rois_exact;
  for (const PairResult& p : rows_[0].result.pairs) world_candidates_ += p.candidates;
  if (suite_.progress) suite_.progress(f + 1, suite_.frames);
}

// --scaling: the default row and the scaling row again over the frames, the two alone, alternating
// frame by frame (which goes first alternates too), after one untimed frame each. Side by side
// with the other methods, the scaling row's workers wake after seconds of the others' work, and
// on a virtual machine that wake can cost tens of milliseconds in a process of several GB
// (docs/performance.md, "Threads"); a program that calls collide() frame after frame keeps them
// awake, and this pass times that.
void SuiteRun::scaling_pass() {
  Row* pair[2] = {&rows_[0], &rows_[scaling_]};
  suite_.frame(0, objects_);
  for (Row* r : pair) run_peelcd(*r);
  for (std::size_t f = 0; f < suite_.frames; ++f) {
    suite_.frame(f, objects_);
    for (std::size_t k = 0; k < 2; ++k) {
      const std::size_t i = (f + k) % 2;
      run_peelcd(*pair[i]);
      alone_ms_[i].push_back(pair[i]->result.timings.total);
    }
  }
  // Then the default row's World under the lane model (World::model_lanes): planned for the
  // scaling row's threads, run on one, its loops replayed on them: what the work's balance alone
  // allows, to hold the measured ratio against.
  Row& base = rows_[0];
  if (threads_ != 1 || suite_.scaling_threads < 2) return;
  base.world->model_lanes(suite_.scaling_threads);
  suite_.frame(0, objects_);
  run_peelcd(base);
  for (std::size_t f = 0; f < suite_.frames; ++f) {
    suite_.frame(f, objects_);
    run_peelcd(base);
    double wall = 0.0, span = 0.0;
    for (const LaneLoop& l : base.world->lane_loops()) wall += l.wall_ms, span += l.span_ms;
    const double total = base.result.timings.total;  // (the bodies brought to the frame included)
    if (total > 0.0) modelled_.push_back((total - wall + span) / total);
  }
  base.world->model_lanes(0);
}

void SuiteRun::print_table(bool heap_kept) const {
  std::vector<double> med(rows_.size());
  for (std::size_t m = 0; m < rows_.size(); ++m) med[m] = median(rows_[m].ms);
  // The FCL ratio is against the faster of its ways with deforming objects; the best peer is
  // the fastest of the CGAL and peer rows (a variant is no peer's default).
  const std::size_t fc = fastest(med, [](const Row& r) { return r.peer && r.peer->library() == "FCL"; });
  const std::size_t best = fastest(med, [](const Row& r) { return r.kind == Kind::cgal || (r.peer && !r.peer->variant()); });
  const int tile = suite_.res ? suite_.res : base_.budget;
  std::printf("peelcd bench: %s, %zu frames, %zu objects, %zu triangles, %s, %s (%s), medians per frame after an untimed pass\n",
              suite_.scene.c_str(), suite_.frames, objects_.size(), triangles_,
              suite_.res ? (std::to_string(tile) + "^2 per ROI").c_str()
                         : ("a " + std::to_string(tile) + "^2 budget shared by the ROIs").c_str(),
              suite_.stage->backend().c_str(), suite_.stage->renderer().c_str());
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("threads: %u for every method (CGAL, FCL: object pairs; peelcd: object pairs, the node pairs of one pair's "
              "trees (World), host resolve lanes); llvmpipe %s; freed memory %s\n",
              threads_, lp ? (std::string("LP_NUM_THREADS=") + lp).c_str() : "its default (one per core)",
              heap_kept ? "kept in the process (mallopt)" : "returned as the allocator decides");
  std::printf("World: %.0f candidate couples per frame (mean, default row; on the image route in %zu of %zu timed "
              "frames); frame API router: %zu of %zu ROIs to the exact CPU path over the timed frames\n",
              suite_.frames ? double(world_candidates_) / double(suite_.frames) : 0.0, world_image_frames_,
              suite_.frames, rois_exact_, rois_);
  std::printf("%-38s %10s %9s %8s %7s %8s %8s %8s %8s\n", "method", "median ms", "stage ms", "miss", "false", "x CGAL",
              "x FCL", "x best", "x floor");
  for (std::size_t m = 0; m < rows_.size(); ++m) {
    const Row& r = rows_[m];
    std::printf("%-38s %10.2f", r.name.c_str(), med[m]);
    if (r.peelcd())
      std::printf(" %9.2f", median(r.stage_ms));
    else
      std::printf(" %9s", "-");
    if (r.floor())
      std::printf(" %8s %7s", "-", "-");
    else
      std::printf(" %7.2f%% %7zu", 100.0 * r.score.miss_ratio(), r.score.false_contacts);
    if (m < cg_ || m == pairs_ || (scaling_ && m == scaling_)) {
      const std::size_t floor = r.opt.cull == Cull::box ? fl_ : cfl_;
      std::printf(" %8.2f %8.2f %8.2f %8.2f\n", med[m] / med[cg_], med[m] / med[fc], med[m] / med[best],
                  med[floor] > 0 ? med[m] / med[floor] : 0.0);
    } else {
      std::printf("\n");
    }
  }
  std::printf("(miss / false: over all frames against the exact pairs; FCL's, Embree's and Bullet's triangle tests are not exact\n"
              " (Embree, Bullet: Moller's test as published, in float; 'scaled test': tri_tri_float(), a variant, not in x best);\n"
              " the floor finds nothing.\n"
              " stage ms: the image stage's GPU work, timed on the host to its end (0 on the exact path); the rest is host work.\n"
              " x CGAL: against the cropped CGAL peer; x FCL: against the faster FCL row (%s); x best: against the fastest\n"
              " peer row (%s); x floor: against one bare\n"
              " draw of the triangles the configuration would draw, one view. World rows: their bodies brought to each\n"
              " frame inside the time (poses; a deforming body's vertices and refit; its topology kept while its counts stay,\n"
              " as the float peers keep theirs). pairs only: the default row asking for the colliding triangle pairs\n"
              " alone (DetectOptions::contacts pairs: no segment or kind, as the float peers return them).)\n",
              rows_[fc].name.c_str(), rows_[best].name.c_str());
  // Each peer's setup, in words, and its trees or scenes built and refitted over all frames
  // (docs/performance.md, "The peers").
  std::printf("peer setups:\n");
  for (const std::unique_ptr<Peer>& p : peers_)
    std::printf("  %s: %s; %zu built, %zu refits\n", p->name().c_str(), p->setup().c_str(), p->builds(), p->refits());
  if (scaling_) {
    const double one = median(alone_ms_[0]), many = median(alone_ms_[1]);
    std::printf("scaling: the default World with %u threads / with %u, the two alone after the side-by-side frames, "
                "alternating frame by frame: %.2f (medians %.2f / %.2f ms); side by side with the others (the table): %.2f\n",
                suite_.scaling_threads, threads_, many / one, many, one, med[scaling_] / med[0]);
    if (!modelled_.empty())
      std::printf("scaling by the work's balance alone: %.3f (median; the default World planned for %u lanes, run on one "
                  "thread with its loops' items timed and replayed on %u lanes: World::model_lanes)\n",
                  median(modelled_), suite_.scaling_threads, suite_.scaling_threads);
  }
  print_audit(med);
}

// --audit: each of the bench's FCL, Embree and Bullet rows against its library's plain setup, the
// same frames side by side.
void SuiteRun::print_audit(const std::vector<double>& med) const {
  for (std::size_t plain = 0; plain < rows_.size(); ++plain) {
    const Peer* q = rows_[plain].peer;
    if (!q || !dynamic_cast<const PlainPeer*>(q)) continue;
    for (std::size_t m = 0; m < rows_.size(); ++m) {
      const Peer* p = rows_[m].peer;
      if (!p || m == plain || p->library() != q->library() || p->variant()) continue;
      std::printf("audit: %s / the plain setup: %.2f (medians %.3f / %.3f ms; pairs %zu / %zu over the frames)%s\n",
                  rows_[m].name.c_str(), med[m] / med[plain], med[m], med[plain], rows_[m].score.found,
                  rows_[plain].score.found, threads_ == 1 ? "" : " (the plain setup runs one thread)");
    }
  }
}

// The median of one field of a row's frames.
double median_of(const std::vector<Split>& v, double Split::*f) {
  std::vector<double> x;
  for (const Split& s : v) x.push_back(s.*f);
  return median(x);
}

// The image stage's share of each peelcd row that peeled: what the host did outside GL, what the
// GPU's passes took, what went up the bus, and how many candidates reached the host's exact test.

void SuiteRun::print_image_work() const {
  const auto med = median_of;
  const double exact_ms = median(rows_[0].ms);
  bool any = false;
  for (const Row& r : rows_) {
    if (!r.peelcd() || med(r.split, &Split::rois_peeled) == 0) continue;
    if (!any) {
      std::printf("\nimage work per frame (medians over the frames; the rows above, the same runs):\n");
      std::printf("%-38s %8s %8s %8s %8s %8s %7s %7s %8s %6s %9s %9s %9s %9s %9s %6s\n", "method", "frame", "host",
                  "GL wait", "raster", "compute", "select", "cover", "transfer", "x dflt", "KB up", "KB mesh", "apart",
                  "cands", "colliding", "c/col");
      any = true;
    }
    const double host = med(r.split, &Split::total) - med(r.split, &Split::wait);
    const double colliding = med(r.split, &Split::colliding), candidates = med(r.split, &Split::candidates);
    std::printf("%-38s %8.2f %8.2f %8.2f", r.name.c_str(), med(r.split, &Split::total), host, med(r.split, &Split::wait));
    if (gl_stage_.pass_timing())
      std::printf(" %8.2f %8.2f %7.2f %7.2f %8.2f", med(r.split, &Split::raster), med(r.split, &Split::compute),
                  med(r.split, &Split::select), med(r.split, &Split::cover), med(r.split, &Split::transfer));
    else
      std::printf(" %8s %8s %7s %7s %8s", "-", "-", "-", "-", "-");
    std::printf(" %6.2f %9.1f %9.1f %9.0f %9.0f %9.0f %6.2f\n", exact_ms > 0 ? host / exact_ms : 0.0,
                med(r.split, &Split::uploaded) / 1024.0, med(r.split, &Split::geometry) / 1024.0,
                med(r.split, &Split::apart), candidates, colliding, colliding > 0 ? candidates / colliding : 0.0);
  }
  if (!any) return;
  std::size_t untimed = 0;
  for (const Row& r : rows_)
    for (const Split& s : r.split) untimed += s.untimed;
  if (untimed)
    std::printf("%zu GPU passes over all frames gave an impossible time (longer than the stage call) and are left out\n",
                untimed);
  std::printf("(frame: the row's median ms; host: frame - GL wait, the host's work outside waits for the GPU (reads back,\n"
              " maps, query results, and memory barriers, where a software renderer finishes its work); raster, compute,\n"
              " transfer: GPU time of draws, dispatches and uploads/clears/copies by GL timer queries%s (select, cover:\n"
              " the parts of compute that select the batch's triangles and cover conservative views); x dflt: host\n"
              " against the default World row's median frame (%.2f ms); KB up: bytes the host wrote into GL buffers, KB\n"
              " mesh: of those, corners, indices and draw entries; apart: texel couples the GPU resolve's certified filter\n"
              " proved apart and did not read back; cands: triangle couples the host tested exactly; c/col: cands per\n"
              " colliding pair.)\n",
              gl_stage_.pass_timing() ? "" : " (off: --no-gpu-timers)", exact_ms);
  print_host_steps();
}

// The same rows' frames by the host's steps (Timings), medians of each: where the host's work goes.
void SuiteRun::print_host_steps() const {
  const auto med = median_of;
  std::printf("\nimage work per frame by step (medians, ms; the same runs):\n");
  std::printf("%-38s %8s %8s %8s %8s %8s %8s %8s\n", "method", "frame", "boxes", "views", "stage", "readback", "exact",
              "other");
  for (const Row& r : rows_) {
    if (!r.peelcd() || med(r.split, &Split::rois_peeled) == 0) continue;
    const double frame = med(r.split, &Split::total), boxes = med(r.split, &Split::boxes),
                 views = med(r.split, &Split::views), stage = med(r.split, &Split::stage),
                 readback = med(r.split, &Split::readback), exact = med(r.split, &Split::exact);
    std::printf("%-38s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f\n", r.name.c_str(), frame, boxes, views, stage, readback,
                exact, frame - boxes - views - stage - readback - exact);
  }
  std::printf("(boxes: bounds, broad phase, the World's tree traversals, culling, routing; views: the views and their\n"
              " triangles gathered (the World's image route: regions, tiles and jobs; moving meshes' vertices into the GPU's\n"
              " buffer; the copying route's candidates' triangles) and uploaded; stage:\n"
              " the image stage's draw and dispatch calls on the host, GL waits included; readback: layers and PCS read\n"
              " back; exact: the exact tests of the candidates, relations; other: the rest (refits, the World's\n"
              " routing and result assembly). Medians of each column: the columns need not sum to the frame.)\n");
}

void SuiteRun::print_phases() const {
  std::printf("\nper phase, median ms:\n%-7s", "phase");
  for (const Row& r : rows_) std::printf(" %9s", r.column.c_str());
  std::printf(" %9s %9s %9s\n", "dflt/CGAL", "dflt/FCL", "dflt/best");
  for (int p = 0; p < suite_.phases; ++p) {
    std::printf("(%c)    ", char('a' + p));
    if (rows_[0].phase_ms[std::size_t(p)].empty()) {  // fewer frames than phases
      std::printf(" no frames\n");
      continue;
    }
    std::vector<double> pm(rows_.size());
    for (std::size_t m = 0; m < rows_.size(); ++m) std::printf(" %9.2f", pm[m] = median(rows_[m].phase_ms[std::size_t(p)]));
    const std::size_t fc = fastest(pm, [](const Row& r) { return r.peer && r.peer->library() == "FCL"; });
    const std::size_t best = fastest(pm, [](const Row& r) { return r.kind == Kind::cgal || (r.peer && !r.peer->variant()); });
    std::printf(" %9.2f %9.2f %9.2f\n", pm[0] / pm[cg_], pm[0] / pm[fc], pm[0] / pm[best]);
  }
}

}  // namespace

std::string run_suite(const Suite& suite) {
  auto* gl_stage = dynamic_cast<gl::GlImageStage*>(suite.stage.get());
  if (!gl_stage) throw std::invalid_argument("peelcd bench: the benchmark times GL stages (use osmesa or egl)");
  if (suite.res > 0 && suite.res > gl_stage->max_resolution())
    throw std::invalid_argument("peelcd bench: --res " + std::to_string(suite.res) + " is above GL_MAX_TEXTURE_SIZE");
  // Freed memory stays in the process: the methods take turns on every frame, and one that frees
  // gigabytes (the CGAL reference, FCL's cropped trees) would otherwise hand them back to the
  // kernel and make whichever method runs next pay for it (2-3x slower frames measured:
  // docs/performance.md, "Side by side"). Every method gets the same allocator; the library
  // itself never changes it.
  const bool heap_kept = suite.keep_freed_memory && keep_freed_memory();
  gl_stage->set_pass_timing(suite.gpu_timers);
  SuiteRun run(suite, *gl_stage);
  std::string csv = run.run(heap_kept);
  gl_stage->set_pass_timing(false);
  return csv;
}

}  // namespace peelcd::bench
