#include "peelcd/core/detector.h"
#include "peelcd/core/clock.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/cull.h"
#include "peelcd/core/options.h"
#include "peelcd/core/reference.h"
#include "peelcd/core/worker_pool.h"
#include "exclusive_use.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>
#include <thread>

namespace peelcd {
namespace {

std::string object_label(const Object& o, std::size_t i) {
  return "object " + std::to_string(i) + (o.name.empty() ? "" : " '" + o.name + "'");
}

// Gives the caller's context back when the frame ends, also on an exception.
struct FrameScope {
  ImageStage* stage = nullptr;
  ~FrameScope() {
    if (stage) stage->end_frame();
  }
};

}  // namespace

void validate_objects(const std::vector<Object>& objects, bool float_range) {
  for (std::size_t i = 0; i < objects.size(); ++i) validate_object(objects[i], i, float_range);
}

void validate_objects(const std::vector<const Object*>& objects, bool float_range) {
  for (std::size_t i = 0; i < objects.size(); ++i) validate_object(*objects[i], i, float_range);
}

std::string pose_problem(const Eigen::Affine3d& pose) {
  if (!pose.matrix().allFinite()) return "has a NaN or infinite entry";
  const double det = pose.linear().determinant();
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    return "is singular (its rotation/scale part has determinant " + std::to_string(det) +
           ": a zero scale collapses the mesh)";
  return {};
}

std::string coordinate_problem(const Vec3& p, bool float_range) {
  if (!p.allFinite()) return "has a NaN or infinite coordinate";
  if (float_range && p.cwiseAbs().maxCoeff() > kFloatMax) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "(%g, %g, %g) is outside the float range (|x| <= 3.4e38) the image stage works in",
                  p.x(), p.y(), p.z());
    return buf;
  }
  return {};
}

namespace {
// The checks, the object's label built only on failure (a valid frame allocates nothing).
template <class Label>
void check_object(const Object& o, const Label& label, bool float_range) {
  const Mesh& m = o.mesh;
  const auto fail = [&](const std::string& problem) { throw std::invalid_argument("peelcd: " + label() + problem); };
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (!m.vertices[v].allFinite() || (float_range && m.vertices[v].cwiseAbs().maxCoeff() > kFloatMax))
      fail(": vertex " + std::to_string(v) + " " + coordinate_problem(m.vertices[v], float_range));
  const std::size_t n = m.vertices.size();
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (std::uint32_t v : m.triangles[f])
      if (v >= n)
        fail(": triangle " + std::to_string(f) + " uses vertex " + std::to_string(v) + " but the mesh has " +
             std::to_string(n) + " vertices");
  // A layer texel stores object << 31 | ID + 1: IDs must stay below 2^31 - 1.
  if (std::max(m.triangles.size(), m.vertices.size()) >= 0x7fffffffu)
    fail(" has 2^31 - 1 or more triangles or vertices; IDs hold 31 bits");
  if (o.rigid) {
    if (!o.rigid->shape) fail(": rigid motion without a shape");
    if (o.rigid->shape->triangles.size() != m.triangles.size())
      fail(": its rigid shape has " + std::to_string(o.rigid->shape->triangles.size()) + " triangles, its world mesh " +
           std::to_string(m.triangles.size()));
    if (const std::string problem = pose_problem(o.rigid->pose); !problem.empty()) fail(": its pose " + problem);
  }
}
}  // namespace

void validate_object(const Object& o, std::size_t i, bool float_range) {
  check_object(o, [&] { return object_label(o, i); }, float_range);
}

void validate_object(const Object& o, const std::string& label, bool float_range) {
  check_object(o, [&] { return label; }, float_range);
}

void validate_options(const DetectOptions& opt, int max_resolution) {
  const char* where = "peelcd: options: ";
  // Every option's range, from the one table (peelcd/core/options.h).
  for (const OptionSpec& spec : option_table())
    if (const std::string problem = check_option(spec, spec.get(opt)); !problem.empty())
      throw std::invalid_argument(std::string(where) + spec.key + " " + problem);
  // And what depends on the stage: its largest view.
  if (opt.resolution > max_resolution)
    throw std::invalid_argument(std::string(where) + "resolution " + std::to_string(opt.resolution) + " is outside 1.." +
                                std::to_string(max_resolution) +
                                " (the image stage's largest view: GL_MAX_TEXTURE_SIZE on GL; 0 = share the budget)");
  if (opt.resolution == 0 && opt.budget > max_resolution)
    throw std::invalid_argument(std::string(where) + "budget " + std::to_string(opt.budget) + " is outside 1.." +
                                std::to_string(max_resolution) + " (the image stage's largest view)");
}

bool triangle_touches(const Mesh& mesh, std::uint32_t t, const Aabb& box) {
  const Tri& f = mesh.triangles[t];
  const Vec3& a = mesh.vertices[f[0]];
  const Vec3& b = mesh.vertices[f[1]];
  const Vec3& c = mesh.vertices[f[2]];
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  return !((hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any());
}

double triangles_in_view(const Mesh& mesh, const RoiView& view, const std::vector<std::uint32_t>* only,
                         std::vector<std::uint32_t>& out) {
  out.clear();
  double min_depth = view.half_depth;
  const Aabb& box = view.box;
  const std::size_t count = only ? only->size() : mesh.triangles.size();
  for (std::size_t i = 0; i < count; ++i) {
    const auto t = only ? (*only)[i] : std::uint32_t(i);
    if (!triangle_touches(mesh, t, box)) continue;
    out.push_back(t);
    const Tri& f = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const Vec3 local = mesh.vertices[f[k]] - view.center;
      min_depth = std::min(min_depth, std::max(-view.half_depth, local.dot(view.frame.d)));
    }
  }
  return min_depth;
}

namespace {
// Fitted by `peelcd calibrate` (2 cores, 2026-11-23, after the sign-once narrow phase and the
// one-round culling of the exact path; docs/performance.md): 0.16 us per triangle kept by the
// first culling round (the router's count), no fixed part measurable.
constexpr double kExactViewMs = 0.0;
constexpr double kExactTriangleUs = 0.16;
// The scan of culling's first round, per triangle of the two objects (`peelcd calibrate`, large
// meshes; docs/performance.md).
constexpr double kScanUs = 0.055;
}  // namespace

StageCost exact_path_cost() {
  // Fitted by `peelcd calibrate` (docs/performance.md, "The stage router").
  return StageCost{kExactViewMs, kExactTriangleUs, 0.0, kScanUs};
}

void triangles_touching(const Mesh& mesh, const Aabb& box, std::vector<std::uint32_t>& out) {
  out.clear();
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (triangle_touches(mesh, t, box)) out.push_back(t);
}

// The frame's objects through pointers (no copy of any mesh).
struct ObjectRefs {
  const std::vector<const Object*>& p;
  const Object& operator[](std::size_t i) const { return *p[i]; }
  std::size_t size() const { return p.size(); }
};

// The self pairs (i, i) of the objects that ask for self-collision (Object::self or
// DetectOptions::self) and have two triangles or more, merged into the sorted pairs.
template <class Objects>
void add_self_pairs(const Objects& objects, const DetectOptions& opt, std::vector<std::pair<std::size_t, std::size_t>>& pairs) {
  bool any = false;
  for (std::size_t i = 0; i < objects.size(); ++i)
    if ((opt.self || objects[i].self) && objects[i].mesh.triangles.size() >= 2) {
      pairs.emplace_back(i, i);
      any = true;
    }
  if (any) std::sort(pairs.begin(), pairs.end());
}

// One overlapping pair's plan: its ROI, what contact culling kept, its tile.
struct PairPlan {
  std::size_t a = 0, b = 0;
  Aabb roi, region;
  std::size_t in_roi_a = 0, in_roi_b = 0;
  std::size_t scanned = 0;  // triangles of both objects (culling's first round reads them all)
  bool culled_out = false;  // one object has nothing near the other: no contact, no image work
  int tile = 0;
  bool exact = false;  // routed to the exact CPU path
  double predicted_image = 0.0, predicted_exact = 0.0;
  double median_edge = 0.0;  // of the kept triangles (edge_tile_resolution())
  std::vector<std::uint32_t> kept_a, kept_b;
  // A self pair (a == b): the object's vertex representatives (SelfAdjacency) and its self
  // candidates (non-adjacent couples whose boxes overlap), found while planning.
  std::vector<std::uint32_t> rep;
  std::vector<std::uint64_t> self_candidates;
};

struct Detector::Impl {
  std::atomic<std::thread::id> owner{};  // the thread running a frame (ExclusiveUse)
  std::vector<const Object*> pointers;
  std::vector<PairPlan> plans;
  std::vector<int> needs, tiles;
  std::vector<std::uint64_t> direct;  // views resolved exhaustively: triangle pairs, not IDs
  std::vector<Aabb> boxes;
  std::vector<std::pair<std::size_t, std::size_t>> object_pairs;
  const std::vector<std::pair<std::size_t, std::size_t>>* only = nullptr;  // Detector::only_pairs()
  std::vector<std::size_t> order;
  // Per lane of the object-pair loops (lane 0: the calling thread): culling and exact-path scratch.
  struct Lane {
    ContactCull cull;
    std::vector<std::uint64_t> candidates, candidate_scratch;
    BoxScratch boxes;
  };
  std::vector<std::unique_ptr<Lane>> lanes;
  std::unique_ptr<WorkerPool> pool;  // DetectOptions::threads > 1 only
  std::vector<std::size_t> exact_pairs;
  std::vector<std::uint32_t> tris[2];
  std::vector<std::vector<std::uint32_t>> job_tris;  // per job of the frame: A's, B's triangles
  std::vector<PeelJob> jobs;                         // the frame's ROI views, grouped by pair
  std::vector<std::size_t> job_first;                // pair i's jobs: [job_first[i], job_first[i + 1])
  std::vector<PeelResult> peeled;                    // per job (never shrinks: storage reused)
  std::vector<IdPair> pcs_all;
  std::vector<std::uint64_t> candidates, candidate_scratch, pcs_keys;
  IdMap map_a, map_b;
  std::vector<CapturedView>* capture = nullptr;
  StageCost image_cost, exact_cost;  // the router's models this frame (ImageStage::router_*_cost())
  BoxScratch box_scratch;

  // body(i, lane) for every i in [0, n): on the calling thread, or spread over the pool's lanes
  // (pairs taken one at a time from a shared counter) when opt.threads asks for more than one.
  // Each pair's work touches only its own plan or result and the lane's scratch.
  template <class Body>
  void for_pairs(std::size_t n, const DetectOptions& opt, Body&& body) {
    unsigned threads = opt.threads;
    if (threads != 1 && n > 1) {
      if (!pool || (threads != 0 && pool->lanes() != threads)) pool = std::make_unique<WorkerPool>(threads);
      threads = pool->lanes();
    }
    while (lanes.size() < std::max(1u, threads)) lanes.push_back(std::make_unique<Lane>());
    if (threads <= 1 || n <= 1) {
      for (std::size_t i = 0; i < n; ++i) body(i, *lanes[0]);
      return;
    }
    std::atomic<std::size_t> next{0};
    auto job = [&](unsigned lane) {
      for (std::size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) body(i, *lanes[lane]);
    };
    pool->run(job);
  }

  // The plans of the frame's overlapping pairs (s.object_pairs): culling, then the tiles. With
  // Cull::contact and a shared budget, each ROI asks for the side that gives its kept triangles'
  // median edge `edge_texels` texels, and the budget is shared by need (allocate_tiles()).
  // Routing (Stage::automatic, Stage::exact) happens after one culling round: the exact CPU path
  // goes on from there (further rounds cost it more than they save), and only the ROIs routed to
  // the image stage are culled again with every round (the tiles shared again with their needs).
  // Stage::image culls every ROI with every round first (dumps and goldens depend on it).
  template <class Objects>
  void plan(const Objects& objects, const DetectOptions& opt) {
    const auto& pairs = object_pairs;
    if (plans.size() < pairs.size()) plans.resize(pairs.size());
    const int equal = opt.resolution > 0 ? opt.resolution : tile_resolution(opt.budget, pairs.size());
    const int first_rounds = opt.stage == Stage::image ? kMaxCullRounds : 1;
    for_pairs(pairs.size(), opt, [&](std::size_t i, Lane& lane) {
      PairPlan& p = plans[i];
      p.a = pairs[i].first;
      p.b = pairs[i].second;
      p.roi = intersection(boxes[p.a], boxes[p.b]);
      p.region = p.roi;
      p.in_roi_a = p.in_roi_b = 0;
      p.scanned = objects[p.a].mesh.triangles.size() + objects[p.b].mesh.triangles.size();
      p.culled_out = false;
      p.tile = equal;
      p.exact = false;
      p.predicted_image = p.predicted_exact = 0.0;
      p.kept_a.clear();
      p.kept_b.clear();
      if (p.a == p.b) {
        plan_self(objects[p.a].mesh, opt, p);
        return;
      }
      if (opt.cull != Cull::contact) {
        if (opt.stage == Stage::image) return;
        // The router and the exact path need the triangles touching the ROI.
        triangles_touching(objects[p.a].mesh, p.roi, p.kept_a);
        triangles_touching(objects[p.b].mesh, p.roi, p.kept_b);
        p.in_roi_a = p.kept_a.size();
        p.in_roi_b = p.kept_b.size();
        p.culled_out = p.kept_a.empty() || p.kept_b.empty();
        return;
      }
      cull_pair(objects, p, first_rounds, lane.cull);
    });
    share_budget(opt);
    route(opt);
    if (opt.stage != Stage::automatic || opt.cull != Cull::contact) return;
    bool any_image = false;
    for (std::size_t i = 0; i < pairs.size(); ++i) any_image = any_image || !(plans[i].culled_out || plans[i].exact);
    if (!any_image) return;
    for_pairs(pairs.size(), opt, [&](std::size_t i, Lane& lane) {
      PairPlan& p = plans[i];
      if (!(p.culled_out || p.exact) && p.a != p.b) cull_pair(objects, p, kMaxCullRounds, lane.cull);
    });
    share_budget(opt);  // the same ROIs share it: the image ROIs' needs now final
  }

  // A self pair's plan: its ROI is the object's box; its candidates are found by a sweep over
  // all its triangles (self_overlap_pairs()), which is its culling too: the triangles kept are
  // those in some candidate, the region their box. The image stage peels them as both objects.
  void plan_self(const Mesh& mesh, const DetectOptions& opt, PairPlan& p) {
    p.scanned = p.in_roi_a = p.in_roi_b = mesh.triangles.size();
    vertex_representatives(mesh, opt.self_adjacency, p.rep);
    p.self_candidates.clear();
    self_overlap_pairs(mesh, nullptr, p.rep, p.self_candidates);
    std::sort(p.self_candidates.begin(), p.self_candidates.end());
    for (const std::uint64_t c : p.self_candidates) {
      p.kept_a.push_back(pair_a(c));
      p.kept_a.push_back(pair_b(c));
    }
    std::sort(p.kept_a.begin(), p.kept_a.end());
    p.kept_a.erase(std::unique(p.kept_a.begin(), p.kept_a.end()), p.kept_a.end());
    p.kept_b = p.kept_a;
    p.culled_out = p.kept_a.empty();
    p.region = Aabb{};
    std::vector<double> edges;
    for (const std::uint32_t t : p.kept_a) {
      const Tri& f = mesh.triangles[t];
      for (int c = 0; c < 3; ++c) p.region.extend(mesh.vertices[f[c]]);
      edges.push_back((mesh.vertices[f[1]] - mesh.vertices[f[0]]).norm());
    }
    p.median_edge = 0.0;
    if (!edges.empty()) {
      std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
      p.median_edge = edges[edges.size() / 2];
    }
    if (opt.cull == Cull::box && !p.culled_out) {  // the image stage peels the whole box
      p.region = p.roi;
      p.kept_a.resize(mesh.triangles.size());
      std::iota(p.kept_a.begin(), p.kept_a.end(), 0u);
      p.kept_b = p.kept_a;
    }
  }

  template <class Objects>
  void cull_pair(const Objects& objects, PairPlan& p, int rounds, ContactCull& cull) {
    cull_to_contact_region(objects[p.a].mesh, objects[p.b].mesh, p.roi, cull, rounds);
    p.region = cull.box;
    p.in_roi_a = cull.stats.in_roi_a;
    p.in_roi_b = cull.stats.in_roi_b;
    p.culled_out = cull.box.empty();
    p.kept_a.assign(cull.kept_a.begin(), cull.kept_a.end());
    p.kept_b.assign(cull.kept_b.begin(), cull.kept_b.end());
    p.median_edge = cull.median_edge;
  }

  // With Cull::contact and a shared budget: each ROI's tile by need (allocate_tiles()), among the
  // ROIs not culled out.
  void share_budget(const DetectOptions& opt) {
    if (opt.cull != Cull::contact || opt.resolution != 0) return;
    const double edge_texels = edge_texels_of(opt);
    needs.clear();
    for (std::size_t i = 0; i < object_pairs.size(); ++i) {
      const PairPlan& p = plans[i];
      if (p.culled_out) continue;
      needs.push_back(edge_tile_resolution(opt.budget, p.region, p.median_edge, edge_texels));
    }
    allocate_tiles(opt.budget, needs, tiles);
    std::size_t next = 0;
    for (std::size_t i = 0; i < object_pairs.size(); ++i) {
      PairPlan& p = plans[i];
      if (p.culled_out) continue;
      p.tile = tiles[next++];
    }
  }

  // The stage router: each ROI to the exact CPU path or the image stage, by the stage's cost
  // model against the exact path's (both linear in the triangles kept, the image stage also in
  // the tile's texels and per view). Deterministic: the models are constants, not timings.
  void route(const DetectOptions& opt) {
    if (opt.stage == Stage::image) return;
    const StageCost exact = exact_cost;
    const StageCost image = image_cost;
    const double views = double(opt.views);
    for (std::size_t i = 0; i < object_pairs.size(); ++i) {
      PairPlan& p = plans[i];
      if (p.culled_out) continue;
      if (opt.stage == Stage::exact) {
        p.exact = true;
        continue;
      }
      const double n = double(p.kept_a.size() + p.kept_b.size());
      const double scan = exact.scan_us * 1e-3 * double(p.scanned);  // paid by both paths
      p.predicted_exact = scan + exact.predict_ms(n, 0.0);
      p.predicted_image = scan + views * image.predict_ms(n, double(p.tile) * double(p.tile));
      p.exact = p.predicted_exact <= p.predicted_image;
    }
  }
};

Detector::Detector(std::shared_ptr<ImageStage> stage) : stage_(std::move(stage)), impl_(std::make_unique<Impl>()) {
  if (!stage_) throw std::invalid_argument("peelcd::Detector: no image stage");
}
Detector::~Detector() = default;

void Detector::capture_layers(std::vector<CapturedView>* sink) { impl_->capture = sink; }
void Detector::only_pairs(const std::vector<std::pair<std::size_t, std::size_t>>* pairs) { impl_->only = pairs; }

FrameResult Detector::detect(const std::vector<Object>& objects, const DetectOptions& opt) {
  FrameResult out;
  detect(objects, opt, out);
  return out;
}

void Detector::detect(const std::vector<Object>& objects, const DetectOptions& opt, FrameResult& out) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  std::vector<const Object*>& ptrs = impl_->pointers;
  ptrs.clear();
  for (const Object& o : objects) ptrs.push_back(&o);
  detect(ptrs, opt, out);
}

void Detector::detect(const std::vector<const Object*>& object_ptrs, const DetectOptions& opt, FrameResult& out) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  Impl& s = *impl_;
  const ObjectRefs objects{object_ptrs};
  ImageStage& stage = *stage_;
  validate_options(opt, stage.max_resolution());
  s.image_cost = stage.router_image_cost();
  s.exact_cost = stage.router_exact_cost();
  for (const Object* o : object_ptrs)
    if (!o) throw std::invalid_argument("peelcd::Detector::detect(): a null object");
  // The image stage works in float: a coordinate beyond float's range is refused unless the
  // frame runs on the exact CPU path alone (exact for every finite double).
  validate_objects(object_ptrs, opt.stage != Stage::exact);

  // `out` is reused: its vectors keep their capacity (tests/alloc/test_alloc.cpp counts it).
  out.reset_counters();
  const auto t_total = Clock::now();

  auto t0 = Clock::now();
  s.boxes.clear();
  for (std::size_t i = 0; i < objects.size(); ++i) s.boxes.push_back(bounds(objects[i].mesh));
  overlapping_pairs(s.boxes, s.object_pairs, s.order);
  if (s.only)  // the caller's pairs alone (sorted, as overlapping_pairs() gives them)
    s.object_pairs.erase(std::remove_if(s.object_pairs.begin(), s.object_pairs.end(),
                                        [&](const std::pair<std::size_t, std::size_t>& p) {
                                          return !std::binary_search(s.only->begin(), s.only->end(), p);
                                        }),
                         s.object_pairs.end());
  add_self_pairs(objects, opt, s.object_pairs);
  const auto& pairs = s.object_pairs;
  out.timings.aabb = ms_since(t0);

  FrameScope scope;  // the stage's frame begins at the first ROI it peels
  const std::string& renderer = stage.renderer();
  if (out.renderer != renderer) out.renderer = renderer;
  t0 = Clock::now();
  s.plan(objects, opt);
  out.timings.aabb += ms_since(t0);
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);

  // Pass 1: per pair, the exact path now, or the pair's ROI views as jobs (their triangles kept
  // in s.job_tris); pass 2: every job of the frame peeled in one call (a stage may draw them
  // together); pass 3: per pair, the views' PCS united, expanded and tested exactly.
  std::size_t used = 0;
  s.exact_pairs.clear();
  s.jobs.clear();
  s.job_first.assign(pairs.size() + 1, 0);
  for (std::size_t pi = 0; pi < pairs.size(); ++pi) {
    s.job_first[pi] = s.jobs.size();
    const PairPlan& plan = s.plans[pi];
    const std::size_t ia = plan.a, ib = plan.b;
    if (used == out.pairs.size()) out.pairs.emplace_back();
    PairResult& r = out.pairs[used++];
    r.pcs.clear();
    r.colliding.clear();
    r.layers = r.passes = 0;
    r.views_peeled = r.views_exhaustive = 0;
    r.pcs_count = r.candidates = 0;
    r.triangles_drawn_a = r.triangles_drawn_b = 0;
    r.object_a = ia;
    r.object_b = ib;
    r.roi = plan.roi;
    r.region = plan.region;
    r.triangles_in_roi_a = plan.in_roi_a;
    r.triangles_in_roi_b = plan.in_roi_b;
    r.resolution = plan.tile;
    r.epsilon = 0.0;
    r.a_first = false;
    r.exact_stage = plan.exact;
    r.predicted_image_ms = plan.predicted_image;
    r.predicted_exact_ms = plan.predicted_exact;
    if (plan.culled_out) continue;  // no triangle of one object near the other: no contact
    const Mesh& ma = objects[ia].mesh;
    const Mesh& mb = objects[ib].mesh;
    if (plan.exact) {  // the exact CPU path, after this loop (object pairs over opt.threads)
      r.resolution = 0;
      s.exact_pairs.push_back(pi);
      continue;
    }
    const std::vector<std::uint32_t>* only_a = opt.cull == Cull::contact ? &plan.kept_a : nullptr;
    const std::vector<std::uint32_t>* only_b = opt.cull == Cull::contact ? &plan.kept_b : nullptr;
    for (std::size_t v = 0; v < frame_count; ++v) {
      const RoiView view = make_padded_roi_view(r.region, s.boxes[ia], s.boxes[ib], frames[v], r.resolution);
      if (v == 0) r.epsilon = opt.epsilon > 0.0 ? opt.epsilon : view.texel();

      t0 = Clock::now();
      // Each view gathers its own triangles: the pad follows that view's texel size.
      const std::size_t j = s.jobs.size();
      if (s.job_tris.size() < 2 * (j + 1)) s.job_tris.resize(2 * (j + 1));
      std::vector<std::uint32_t>& tris_a = s.job_tris[2 * j];
      std::vector<std::uint32_t>& tris_b = s.job_tris[2 * j + 1];
      const double min_a = triangles_in_view(ma, view, only_a, tris_a);
      const double min_b = triangles_in_view(mb, view, only_b, tris_b);
      out.timings.upload += ms_since(t0);
      if (v == 0) {
        r.triangles_drawn_a = tris_a.size();
        r.triangles_drawn_b = tris_b.size();
        if (opt.cull == Cull::box) {  // nothing culled: what touches the (padded) ROI
          r.triangles_in_roi_a = r.triangles_drawn_a;
          r.triangles_in_roi_b = r.triangles_drawn_b;
        }
        r.a_first = min_a > min_b;  // the farther object first; ties: B first
      }
      if (tris_a.empty() || tris_b.empty()) continue;  // no contact possible, no image work

      PeelJob& job = s.jobs.emplace_back();
      job.objects[0] = &objects[ia];
      job.objects[1] = &objects[ib];
      job.view = view;  // job.triangles are set below: s.job_tris may still move
      job.pair_index = used - 1;
      job.view_index = int(v);
      job.ids = opt.ids;
      job.peel = opt.peel;
      job.epsilon = r.epsilon;
      job.slope = opt.slope;
      job.first = min_a > min_b ? 0 : 1;
      job.capture = s.capture != nullptr;
      job.conservative = opt.conservative;
    }
  }
  s.job_first[pairs.size()] = s.jobs.size();

  // The exact CPU path: every couple of kept triangles whose boxes overlap, tested exactly.
  if (!s.exact_pairs.empty()) {
    t0 = Clock::now();
    s.for_pairs(s.exact_pairs.size(), opt, [&](std::size_t k, Impl::Lane& lane) {
      const std::size_t pi = s.exact_pairs[k];
      const PairPlan& plan = s.plans[pi];
      PairResult& r = out.pairs[pi];
      const Mesh& ma = objects[plan.a].mesh;
      const Mesh& mb = objects[plan.b].mesh;
      if (plan.a == plan.b) {  // self: the candidates planning found
        r.candidates = plan.self_candidates.size();
        self_narrow_phase(ma, plan.self_candidates, r.colliding, opt.max_contacts);
        return;
      }
      lane.candidates.clear();
      box_overlap_pairs(ma, plan.kept_a, mb, plan.kept_b, lane.candidates, &lane.boxes);
      sort_unique_pairs(lane.candidates, lane.candidate_scratch);
      r.candidates = lane.candidates.size();
      narrow_phase(ma, mb, lane.candidates, r.colliding, /*boxes_overlap=*/true, opt.max_contacts);
    });
    out.rois_exact = s.exact_pairs.size();
    out.timings.cpu += ms_since(t0);
  }
  for (std::size_t j = 0; j < s.jobs.size(); ++j) {
    s.jobs[j].triangles[0] = &s.job_tris[2 * j];
    s.jobs[j].triangles[1] = &s.job_tris[2 * j + 1];
  }

  if (!s.jobs.empty()) {
    stage.counters = StageCounters{};
    stage.begin_frame();
    scope.stage = &stage;
    if (s.peeled.size() < s.jobs.size()) s.peeled.resize(s.jobs.size());
    stage.peel_batch(s.jobs.data(), s.jobs.size(), s.peeled.data(), out.timings);
    out.gl_draws = stage.counters.draws;
    out.gl_dispatches = stage.counters.dispatches;
    out.gl_readbacks = stage.counters.readbacks;
    out.bytes_uploaded = stage.counters.bytes_uploaded;
    out.bytes_read = stage.counters.bytes_read;
    out.geometry_bytes = stage.counters.geometry_bytes;
    out.gl_deep_texels = stage.counters.deep_texels;
    out.views_host_resolved = stage.counters.views_host_resolved;
  }

  for (std::size_t pi = 0; pi < pairs.size(); ++pi) {
    const PairPlan& plan = s.plans[pi];
    if (plan.culled_out || plan.exact) continue;
    PairResult& r = out.pairs[pi];
    const Mesh& ma = objects[plan.a].mesh;
    const Mesh& mb = objects[plan.b].mesh;
    std::vector<IdPair>& all_pcs = s.pcs_all;
    all_pcs.clear();
    s.direct.clear();
    for (std::size_t j = s.job_first[pi]; j < s.job_first[pi + 1]; ++j) {
      const PeelJob& job = s.jobs[j];
      PeelResult& one = s.peeled[j];
      ++out.rois_peeled;
      ++r.views_peeled;
      out.gl_passes += one.gl_passes;
      out.pcs_readbacks += one.pcs_readbacks;
      out.triangles_uploaded += one.triangles_uploaded;
      out.triangles_indexed += one.triangles_indexed;
      out.shape_uploads += one.shape_uploads;
      if (one.exhaustive) {  // the stage could not resolve the view: every couple of boxes
        ++out.views_exhaustive;
        ++r.views_exhaustive;
        t0 = Clock::now();
        box_overlap_pairs(ma, *job.triangles[0], mb, *job.triangles[1], s.direct, &s.box_scratch);
        out.timings.cpu += ms_since(t0);
      }
      if (s.capture) {
        CapturedView& c = s.capture->emplace_back();
        c.pair = pi;
        c.view = job.view_index;
        c.roi = job.view;
        c.a_first = job.first == 0;
        c.epsilon_window = one.epsilon_window;
        c.slope = one.slope;
        c.layers = std::move(one.captured);
        c.pcs = one.pcs;
        std::sort(c.pcs.begin(), c.pcs.end());
        c.pcs.erase(std::unique(c.pcs.begin(), c.pcs.end()), c.pcs.end());
      }
      r.layers = std::max(r.layers, one.layers);
      r.passes += one.peel_passes;
      all_pcs.insert(all_pcs.end(), one.pcs.begin(), one.pcs.end());
    }
    if (r.triangles_drawn_a == 0 || r.triangles_drawn_b == 0) continue;

    t0 = Clock::now();
    // Sorted and unique through the radix sort of packed pairs (the views repeat most PCS).
    s.pcs_keys.clear();
    for (const IdPair& p : all_pcs) s.pcs_keys.push_back(pack_pair(p.a, p.b));
    sort_unique_pairs(s.pcs_keys, s.candidate_scratch);
    all_pcs.clear();
    for (const std::uint64_t k : s.pcs_keys) all_pcs.push_back(IdPair{pair_a(k), pair_b(k)});
    r.pcs_count = all_pcs.size();
    r.pcs.assign(all_pcs.begin(), all_pcs.end());
    s.map_a.rebuild(ma, opt.ids);
    s.map_b.rebuild(mb, opt.ids);
    s.candidates.clear();
    expand_pcs(all_pcs, s.map_a, s.map_b, s.candidates, s.candidate_scratch);
    if (!s.direct.empty()) {
      s.candidates.insert(s.candidates.end(), s.direct.begin(), s.direct.end());
      sort_unique_pairs(s.candidates, s.candidate_scratch);
    }
    if (plan.a == plan.b) self_candidates(ma, plan.rep, s.candidates);  // one object peeled as both
    r.candidates = s.candidates.size();
    if (plan.a == plan.b)
      self_narrow_phase(ma, s.candidates, r.colliding, opt.max_contacts);
    else
      narrow_phase(ma, mb, s.candidates, r.colliding, false, opt.max_contacts);
    out.timings.cpu += ms_since(t0);
  }
  out.pairs.resize(used);
  // Relations (containment where no contact) and, asked for, volumes.
  t0 = Clock::now();
  relate_pairs(out.pairs, [&](std::size_t i) -> const Mesh& { return objects[i].mesh; }, s.boxes, opt);
  out.timings.cpu += ms_since(t0);
  out.timings.total = ms_since(t_total);
}

void Detector::for_each_view(const std::vector<Object>& objects_in, const DetectOptions& opt,
                             const std::function<void(const PeelJob&)>& fn) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  Impl& s = *impl_;
  validate_options(opt, stage_->max_resolution());
  validate_objects(objects_in, true);
  std::vector<const Object*> ptrs;
  for (const Object& o : objects_in) ptrs.push_back(&o);
  const ObjectRefs objects{ptrs};
  s.boxes.clear();
  for (const Object& o : objects_in) s.boxes.push_back(bounds(o.mesh));
  overlapping_pairs(s.boxes, s.object_pairs, s.order);
  add_self_pairs(objects, opt, s.object_pairs);
  s.plan(objects, opt);
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);
  for (std::size_t pi = 0; pi < s.object_pairs.size(); ++pi) {
    const PairPlan& plan = s.plans[pi];
    if (plan.culled_out || plan.exact) continue;
    const std::size_t ia = plan.a, ib = plan.b;
    const std::vector<std::uint32_t>* only_a = opt.cull == Cull::contact ? &plan.kept_a : nullptr;
    const std::vector<std::uint32_t>* only_b = opt.cull == Cull::contact ? &plan.kept_b : nullptr;
    double epsilon = opt.epsilon;
    for (std::size_t v = 0; v < frame_count; ++v) {
      PeelJob job;
      job.view = make_padded_roi_view(plan.region, s.boxes[ia], s.boxes[ib], frames[v], plan.tile);
      job.view_index = int(v);
      if (v == 0 && !(epsilon > 0.0)) epsilon = job.view.texel();
      const double min_a = triangles_in_view(objects[ia].mesh, job.view, only_a, s.tris[0]);
      const double min_b = triangles_in_view(objects[ib].mesh, job.view, only_b, s.tris[1]);
      if (s.tris[0].empty() || s.tris[1].empty()) continue;
      job.pair_index = pi;
      job.objects[0] = &objects[ia];
      job.objects[1] = &objects[ib];
      job.triangles[0] = &s.tris[0];
      job.triangles[1] = &s.tris[1];
      job.ids = opt.ids;
      job.peel = opt.peel;
      job.epsilon = epsilon;
      job.slope = opt.slope;
      job.first = min_a > min_b ? 0 : 1;
      job.conservative = opt.conservative;
      fn(job);
    }
  }
}

}  // namespace peelcd
