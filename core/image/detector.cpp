#include "peelcd/core/image/detector.h"
#include "pair_plan.h"
#include "peelcd/core/exact/proximity.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/clock.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/options.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/worker_pool.h"
#include "peelcd/core/exclusive_use.h"

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

bool triangle_touches(const Mesh& mesh, std::uint32_t t, const Aabb& box) {
  const Tri& f = mesh.triangles[t];
  const Vec3& a = mesh.vertices[f[0]];
  const Vec3& b = mesh.vertices[f[1]];
  const Vec3& c = mesh.vertices[f[2]];
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  return !((hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any());
}

void triangles_touching(const Mesh& mesh, const Aabb& box, std::vector<std::uint32_t>& out) {
  out.clear();
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (triangle_touches(mesh, t, box)) out.push_back(t);
}

const std::vector<std::uint32_t>& job_triangles(const PeelJob& job, int slot, std::vector<std::uint32_t>& scratch) {
  if (job.triangles[slot]) return *job.triangles[slot];
  const Object& object = *job.objects[slot];
  if (object.moving && object.moving->source) {  // a moving mesh: its world-space triangles
    const Mesh& mesh = *object.moving->source;
    const Aabb box = job.view.box.grown(job.grow);
    scratch.clear();
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      if (triangle_touches(mesh, t, box)) scratch.push_back(t);
    return scratch;
  }
  if (!object.rigid || !object.rigid->shape)
    throw std::invalid_argument("peelcd::PeelJob: no triangle list for '" + object.name +
                                "', which has neither a rigid shape nor a moving mesh");
  const Mesh& shape = *object.rigid->shape;
  const Eigen::Affine3d& pose = object.rigid->pose;
  const Aabb box = job.view.box.grown(job.grow);
  scratch.clear();
  for (std::uint32_t t = 0; t < shape.triangles.size(); ++t) {
    const Tri& f = shape.triangles[t];
    const Vec3 a = pose * shape.vertices[f[0]], b = pose * shape.vertices[f[1]], c = pose * shape.vertices[f[2]];
    const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    if (!((hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any())) scratch.push_back(t);
  }
  return scratch;
}

double triangles_in_view(const Mesh& mesh, const RoiView& view, const std::vector<std::uint32_t>* only,
                         std::vector<std::uint32_t>& out, double grow) {
  out.clear();
  double min_depth = view.half_depth;
  const Aabb box = view.box.grown(grow);
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


using detail::FramePlan;
using detail::ObjectRefs;
using detail::PairLane;
using detail::PairPlan;

struct Detector::Impl {
  std::atomic<std::thread::id> owner{};  // the thread running a frame (ExclusiveUse)
  std::vector<const Object*> pointers;
  FramePlan plan;
  detail::PairLoop loop;
  const std::vector<detail::IndexPair>* only = nullptr;  // Detector::only_pairs()
  std::vector<std::size_t> exact_pairs;
  std::vector<char> near_found;  // per pair: `near` found from its candidates (relate_pairs skips its search)
  std::vector<std::uint32_t> tris[2];
  std::vector<std::vector<std::uint32_t>> job_tris;  // per job of the frame: A's, B's triangles
  std::vector<PeelJob> jobs;                         // the frame's ROI views, grouped by pair
  std::vector<std::size_t> job_first;                // pair i's jobs: [job_first[i], job_first[i + 1])
  std::vector<PeelResult> peeled;                    // per job (never shrinks: storage reused)
  std::vector<std::uint64_t> direct;                 // views resolved exhaustively: triangle pairs
  std::vector<IdPair> pcs_all;
  std::vector<std::uint64_t> candidates, candidate_scratch, pcs_keys;
  IdMap map_a, map_b;
  std::vector<CapturedView>* capture = nullptr;
  BoxScratch box_scratch;

  // The steps of Detector::detect(), in order.
  void start_pair(std::size_t pi, PairResult& r) const;
  void add_jobs(const ObjectRefs& objects, const DetectOptions& opt, std::size_t pi, const ViewFrame* frames,
                std::size_t frame_count, PairResult& r, Timings& timings);
  void exact_path(const ObjectRefs& objects, const DetectOptions& opt, FrameResult& out);
  void peel(ImageStage& stage, FrameResult& out);
  void gather_views(std::size_t pi, FrameResult& out);
  void resolve_pair(const ObjectRefs& objects, const DetectOptions& opt, std::size_t pi, FrameResult& out);
};

Detector::Detector(std::shared_ptr<ImageStage> stage) : stage_(std::move(stage)), impl_(std::make_unique<Impl>()) {
  if (!stage_) throw std::invalid_argument("peelcd::Detector: no image stage");
}
Detector::~Detector() = default;

void Detector::capture_layers(std::vector<CapturedView>* sink) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  impl_->capture = sink;
}
void Detector::only_pairs(const std::vector<std::pair<std::size_t, std::size_t>>* pairs) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  impl_->only = pairs;
}

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

// A frame: the pairs, their plans (culling, tiles, routes); per pair the exact path or its ROI
// views as jobs; every job peeled in one call of the stage (it may draw them together); per
// peeled pair the views' PCS united, expanded and tested exactly; the relations.
void Detector::detect(const std::vector<const Object*>& object_ptrs, const DetectOptions& opt, FrameResult& out) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::Detector");
  Impl& s = *impl_;
  const ObjectRefs objects{object_ptrs};
  ImageStage& stage = *stage_;
  validate_options(opt, stage.max_resolution());
  s.plan.image_cost = stage.router_image_cost();
  s.plan.exact_cost = stage.router_exact_cost();
  for (const Object* o : object_ptrs)
    if (!o) throw std::invalid_argument("peelcd::Detector::detect(): a null object");
  // The image stage works in float: a coordinate beyond float's range is refused unless the
  // frame runs on the exact CPU path alone (exact for every finite double).
  validate_objects(object_ptrs, opt.stage != Stage::exact);

  // `out` is reused: its vectors keep their capacity (tests/alloc/test_alloc.cpp counts it).
  out.reset_counters();
  const auto t_total = Clock::now();
  auto t0 = Clock::now();
  s.plan.find_pairs(objects, opt, s.only);
  const std::size_t n = s.plan.pairs.size();
  StageFrameScope scope;  // the stage's frame begins at the first ROI it peels
  const std::string& renderer = stage.renderer();
  if (out.renderer != renderer) out.renderer = renderer;
  s.plan.plan(objects, opt, s.loop);
  out.timings.aabb += ms_since(t0);

  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);
  s.exact_pairs.clear();
  s.near_found.assign(n, 0);
  s.jobs.clear();
  s.job_first.assign(n + 1, 0);
  out.pairs.resize(n);
  for (std::size_t pi = 0; pi < n; ++pi) {
    s.job_first[pi] = s.jobs.size();
    PairResult& r = out.pairs[pi];
    s.start_pair(pi, r);
    const PairPlan& plan = s.plan.plans[pi];
    if (plan.culled_out) continue;  // no triangle of one object near the other: no contact
    if (plan.route.exact) {         // the exact CPU path, after this loop (over opt.threads)
      r.resolution = 0;
      s.exact_pairs.push_back(pi);
      continue;
    }
    s.add_jobs(objects, opt, pi, frames, frame_count, r, out.timings);
  }
  s.job_first[n] = s.jobs.size();
  s.exact_path(objects, opt, out);
  if (!s.jobs.empty()) {
    scope.stage = &stage;
    s.peel(stage, out);
  }
  for (std::size_t pi = 0; pi < n; ++pi)
    if (s.plan.plans[pi].peeled()) s.resolve_pair(objects, opt, pi, out);
  // Relations (containment where no contact) and, asked for, volumes.
  t0 = Clock::now();
  relate_pairs(out.pairs, [&](std::size_t i) -> const Mesh& { return objects[i].mesh; }, s.plan.boxes, opt,
               &s.near_found);
  out.timings.cpu += ms_since(t0);
  out.timings.total = ms_since(t_total);
}

// Pair pi's result from its plan (its vectors' storage kept from frame to frame).
void Detector::Impl::start_pair(std::size_t pi, PairResult& r) const {
  const PairPlan& p = plan.plans[pi];
  r.pcs.clear();
  r.colliding.clear();
  r.layers = r.passes = 0;
  r.views_peeled = r.views_exhaustive = 0;
  r.pcs_count = r.candidates = 0;
  r.triangles_drawn_a = r.triangles_drawn_b = 0;
  r.object_a = p.a;
  r.object_b = p.b;
  r.roi = p.roi;
  r.region = p.region;
  r.triangles_in_roi_a = p.in_roi_a;
  r.triangles_in_roi_b = p.in_roi_b;
  r.resolution = p.tile;
  r.epsilon = 0.0;
  r.a_first = false;
  r.exact_stage = p.route.exact;
  r.margin_fallback = p.margin_fallback;
  r.predicted_image_ms = p.route.predicted_image_ms;
  r.predicted_exact_ms = p.route.predicted_exact_ms;
}

// Pair pi's ROI views as jobs (their triangles kept in job_tris); views where one object has no
// triangle are dropped (no contact possible there).
void Detector::Impl::add_jobs(const ObjectRefs& objects, const DetectOptions& opt, std::size_t pi,
                              const ViewFrame* frames, std::size_t frame_count, PairResult& r, Timings& timings) {
  for (std::size_t v = 0; v < frame_count; ++v) {
    const auto t0 = Clock::now();
    const std::size_t j = jobs.size();
    if (job_tris.size() < 2 * (j + 1)) job_tris.resize(2 * (j + 1));
    std::vector<std::uint32_t>& tris_a = job_tris[2 * j];
    std::vector<std::uint32_t>& tris_b = job_tris[2 * j + 1];
    PeelJob job;
    const auto [min_a, min_b] = make_view_job(objects, plan, pi, opt, frames[v], int(v), r.epsilon, tris_a, tris_b, job);
    timings.upload += ms_since(t0);
    if (v == 0) {
      r.triangles_drawn_a = tris_a.size();
      r.triangles_drawn_b = tris_b.size();
      if (opt.cull == Cull::box) {  // nothing culled: what touches the (padded) ROI
        r.triangles_in_roi_a = r.triangles_drawn_a;
        r.triangles_in_roi_b = r.triangles_drawn_b;
      }
      r.a_first = min_a > min_b;
    }
    if (tris_a.empty() || tris_b.empty()) continue;
    job.capture = capture != nullptr;
    jobs.push_back(job);
  }
}

// The exact CPU path: every couple of kept triangles whose boxes overlap, tested exactly (self
// pairs: the candidates planning found), the pairs spread over opt.threads.
void Detector::Impl::exact_path(const ObjectRefs& objects, const DetectOptions& opt, FrameResult& out) {
  if (exact_pairs.empty()) return;
  const auto t0 = Clock::now();
  loop.run(exact_pairs.size(), opt, [&](std::size_t k, PairLane& lane) {
    const std::size_t pi = exact_pairs[k];
    PairPlan& p = plan.plans[pi];
    PairResult& r = out.pairs[pi];
    const Mesh& ma = objects[p.a].mesh;
    const Mesh& mb = objects[p.b].mesh;
    if (p.a == p.b) {
      r.candidates = p.self_count;
      if (p.self_tested)  // tested while planning (FramePlan::plan_self())
        r.colliding.swap(p.self_contacts);
      else
        self_narrow_phase(ma, p.self_candidates, r.colliding, opt.max_contacts, opt.contacts);
      sort_contacts(r.colliding);  // in traversal order
      return;
    }
    lane.candidates.clear();
    box_overlap_pairs(ma, p.kept_a, mb, p.kept_b, lane.candidates, &lane.boxes, opt.margin);
    sort_unique_pairs(lane.candidates, lane.candidate_scratch);
    r.candidates = lane.candidates.size();
    // With a margin the boxes were grown: each couple's own boxes are tested first.
    narrow_phase(ma, mb, lane.candidates, r.colliding, /*boxes_overlap=*/opt.margin == 0.0, opt.max_contacts,
                 opt.contacts);
    if (opt.margin > 0.0) {
      r.near = near_among(ma, mb, lane.candidates, opt.margin);
      near_found[pi] = 1;
    }
  });
  out.rois_exact = exact_pairs.size();
  out.timings.cpu += ms_since(t0);
}

// Every job of the frame in one call of the stage, and what the stage counted.
void Detector::Impl::peel(ImageStage& stage, FrameResult& out) {
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    jobs[j].triangles[0] = &job_tris[2 * j];
    jobs[j].triangles[1] = &job_tris[2 * j + 1];
  }
  stage.counters = StageCounters{};
  stage.begin_frame();
  if (peeled.size() < jobs.size()) peeled.resize(jobs.size());
  stage.peel_batch(jobs.data(), jobs.size(), peeled.data(), out.timings);
  copy_stage_counters(stage.counters, out);
}

// Pair pi's peeled views: their counters, captures and PCS (into pcs_all), and the couples of the
// views the stage resolved exhaustively (into direct).
void Detector::Impl::gather_views(std::size_t pi, FrameResult& out) {
  PairResult& r = out.pairs[pi];
  pcs_all.clear();
  direct.clear();
  for (std::size_t j = job_first[pi]; j < job_first[pi + 1]; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& one = peeled[j];
    ++out.rois_peeled;
    ++r.views_peeled;
    add_view_counters(one, out);
    if (one.exhaustive) {  // the stage could not resolve the view: every couple of boxes
      ++out.views_exhaustive;
      ++r.views_exhaustive;
      const auto t0 = Clock::now();
      box_overlap_pairs(job.objects[0]->mesh, *job.triangles[0], job.objects[1]->mesh, *job.triangles[1], direct,
                        &box_scratch, 2.0 * job.grow);
      out.timings.cpu += ms_since(t0);
    }
    if (capture) {
      CapturedView& c = capture->emplace_back();
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
    pcs_all.insert(pcs_all.end(), one.pcs.begin(), one.pcs.end());
  }
}

// A peeled pair: its views gathered, the PCS sorted and unique, expanded to triangle couples
// (with the exhaustive views' couples), tested exactly.
void Detector::Impl::resolve_pair(const ObjectRefs& objects, const DetectOptions& opt, std::size_t pi,
                                  FrameResult& out) {
  gather_views(pi, out);
  PairResult& r = out.pairs[pi];
  if (r.triangles_drawn_a == 0 || r.triangles_drawn_b == 0) return;
  const PairPlan& p = plan.plans[pi];
  const Mesh& ma = objects[p.a].mesh;
  const Mesh& mb = objects[p.b].mesh;
  const auto t0 = Clock::now();
  // Sorted and unique through the radix sort of packed pairs (the views repeat most PCS).
  pcs_keys.clear();
  for (const IdPair& c : pcs_all) pcs_keys.push_back(pack_pair(c.a, c.b));
  sort_unique_pairs(pcs_keys, candidate_scratch);
  pcs_all.clear();
  for (const std::uint64_t k : pcs_keys) pcs_all.push_back(IdPair{pair_a(k), pair_b(k)});
  r.pcs_count = pcs_all.size();
  r.pcs.assign(pcs_all.begin(), pcs_all.end());
  candidates.clear();
  if (opt.ids == IdMode::unique) {  // an ID is its triangle: the couples are the sorted PCS keys
    for (const std::uint64_t k : pcs_keys)
      if (pair_a(k) >= ma.triangles.size() || pair_b(k) >= mb.triangles.size())
        throw std::out_of_range("peelcd::Detector: triangle ID out of range");
    candidates.assign(pcs_keys.begin(), pcs_keys.end());
  } else {
    map_a.rebuild(ma, opt.ids);
    map_b.rebuild(mb, opt.ids);
    expand_pcs(pcs_all, map_a, map_b, candidates, candidate_scratch);
  }
  if (!direct.empty()) {
    candidates.insert(candidates.end(), direct.begin(), direct.end());
    sort_unique_pairs(candidates, candidate_scratch);
  }
  if (p.a == p.b) self_candidates(ma, p.rep, candidates);  // one object peeled as both
  r.candidates = candidates.size();
  if (p.a == p.b)
    self_narrow_phase(ma, candidates, r.colliding, opt.max_contacts, opt.contacts);
  else
    narrow_phase(ma, mb, candidates, r.colliding, false, opt.max_contacts, opt.contacts);
  // Conservative: every couple within the margin is a candidate (PeelJob::grow).
  if (opt.margin > 0.0 && p.a != p.b && opt.conservative) {
    r.near = near_among(ma, mb, candidates, opt.margin);
    near_found[pi] = 1;
  }
  out.timings.cpu += ms_since(t0);
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
  s.plan.image_cost = stage_->router_image_cost();
  s.plan.exact_cost = stage_->router_exact_cost();
  s.plan.find_pairs(objects, opt, nullptr);
  s.plan.plan(objects, opt, s.loop);
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);
  for (std::size_t pi = 0; pi < s.plan.pairs.size(); ++pi) {
    if (!s.plan.plans[pi].peeled()) continue;
    double epsilon = 0.0;
    for (std::size_t v = 0; v < frame_count; ++v) {
      PeelJob job;
      make_view_job(objects, s.plan, pi, opt, frames[v], int(v), epsilon, s.tris[0], s.tris[1], job);
      if (s.tris[0].empty() || s.tris[1].empty()) continue;
      job.triangles[0] = &s.tris[0];
      job.triangles[1] = &s.tris[1];
      fn(job);
    }
  }
}

}  // namespace peelcd
