#pragma once
// The frame API's plan of one frame (internal to peelcd_core): the overlapping pairs, per pair
// its ROI, what contact culling kept, its tile and its route (planner.h's router), and each ROI
// view as a PeelJob (one builder, for Detector::detect() and Detector::for_each_view()).

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/worker_pool.h"

#include <atomic>
#include <memory>
#include <utility>
#include <vector>

namespace peelcd::detail {

using IndexPair = std::pair<std::size_t, std::size_t>;

// The frame's objects through pointers (no copy of any mesh).
struct ObjectRefs {
  const std::vector<const Object*>& p;
  const Object& operator[](std::size_t i) const { return *p[i]; }
  std::size_t size() const { return p.size(); }
};

// One overlapping pair's plan: its ROI, what contact culling kept, its tile, its route.
struct PairPlan {
  std::size_t a = 0, b = 0;
  Aabb roi, region;
  std::size_t in_roi_a = 0, in_roi_b = 0;
  std::size_t scanned = 0;  // triangles of both objects (culling's first round reads them all)
  bool culled_out = false;  // one object has nothing near the other: no contact, no image work
  int tile = 0;
  Route route;               // route.exact: to the exact CPU path
  bool margin_fallback = false;  // route.exact because the margin is too wide for the image stage
  double median_edge = 0.0;  // of the kept triangles (edge_tile_resolution())
  std::vector<std::uint32_t> kept_a, kept_b;
  // A self pair (a == b): the object's vertex representatives (SelfAdjacency) and its self
  // candidates (non-adjacent couples whose boxes overlap), found while planning.
  std::vector<std::uint32_t> rep;
  // self_tested: its couples were tested while planning (self_contacts, in traversal order;
  // self_candidates left empty); self_count: its candidate couples either way.
  std::vector<std::uint64_t> self_candidates;
  bool self_tested = false;
  std::size_t self_count = 0;
  std::vector<Contact> self_contacts;
  std::vector<std::uint8_t> marks;  // scratch: a self pair's kept triangles
  bool peeled() const { return !(culled_out || route.exact); }
};

// A self pair of this many triangles or more has its traversal spread over the lanes when the
// frame asks for threads (FramePlan::plan_self()), in kSelfNodePairsPerLane node pairs a lane:
// as the World's (kSplitTriangles, kSplitNodePairsPerLane in core/world/world_impl.h).
constexpr std::size_t kSpreadSelfTriangles = 32768;
constexpr std::size_t kSelfNodePairsPerLane = 32;

// Per lane of the object-pair loops (lane 0: the calling thread): culling and exact-path scratch.
struct PairLane {
  ContactCull cull;
  std::vector<std::uint64_t> candidates, candidate_scratch;
  BoxScratch boxes;
  // A large self pair's traversal spread over the lanes (FramePlan::plan_self()): this lane's
  // contacts, kept triangles and couples, merged after.
  std::vector<Contact> self_contacts;
  std::vector<std::uint8_t> self_marks;
  std::size_t self_count = 0;
  std::vector<BvhNodePair> self_stack;
};

// body(i, lane) for every i in [0, n): on the calling thread, or spread over a pool's lanes
// (WorkerPool::for_each(): a lane's own range of pairs first) when opt.threads asks for more
// than one.
// Each pair's work touches only its own plan or result and the lane's scratch.
class PairLoop {
 public:
  template <class Body>
  void run(std::size_t n, const DetectOptions& opt, Body&& body) {
    unsigned threads = opt.threads;
    if (threads != 1 && n > 1) {
      if (!pool_ || (threads != 0 && pool_->lanes() != threads)) pool_ = std::make_unique<WorkerPool>(threads);
      threads = pool_->lanes();
    }
    while (lanes_.size() < std::max(1u, threads)) lanes_.push_back(std::make_unique<PairLane>());
    if (threads <= 1 || n <= 1) {
      for (std::size_t i = 0; i < n; ++i) body(i, *lanes_[0]);
      return;
    }
    pool_->for_each(n, [&](std::size_t i, unsigned lane) { body(i, *lanes_[lane]); });
  }
  // The lanes run() has made so far (lane 0: the calling thread's scratch).
  template <class Fn>
  void each_lane(Fn&& fn) {
    for (const auto& l : lanes_) fn(*l);
  }
  // How many lanes run() gives `opt` for more than one item (1: the calling thread alone), each
  // lane's scratch made.
  unsigned lanes(const DetectOptions& opt) {
    unsigned threads = 1;
    if (opt.threads != 1) {
      if (!pool_ || (opt.threads != 0 && pool_->lanes() != opt.threads)) pool_ = std::make_unique<WorkerPool>(opt.threads);
      threads = pool_->lanes();
    }
    while (lanes_.size() < threads) lanes_.push_back(std::make_unique<PairLane>());
    return threads;
  }

 private:
  std::vector<std::unique_ptr<PairLane>> lanes_;
  std::unique_ptr<WorkerPool> pool_;  // DetectOptions::threads > 1 only
};

// A frame's plan. find_pairs(), then plan().
class FramePlan {
 public:
  std::vector<Aabb> boxes;         // per object
  std::vector<IndexPair> pairs;    // overlapping pairs (a < b) and self pairs (a == b), sorted
  std::vector<PairPlan> plans;     // per pair (never shrinks: storage reused)
  StageCost image_cost, exact_cost;  // the router's models (ImageStage::router_*_cost())

  // The objects' boxes and the pairs: overlapping boxes (the caller's pairs alone when `only` is
  // set, sorted as overlapping_pairs() gives them), then the self pairs of the objects that ask
  // for self-collision and have two triangles or more.
  void find_pairs(const ObjectRefs& objects, const DetectOptions& opt, const std::vector<IndexPair>* only);

  // The plans of the pairs: culling, then the tiles, then the route. With Cull::contact and a
  // shared budget, each ROI asks for the side that gives its kept triangles' median edge
  // `edge_texels` texels, and the budget is shared by need (allocate_tiles()). Routing
  // (Stage::automatic, Stage::exact) happens after one culling round: the exact CPU path goes on
  // from there (further rounds cost it more than they save), and only the ROIs routed to the
  // image stage are culled again with every round (the tiles shared again with their needs).
  // Stage::image culls every ROI with every round first (dumps and goldens depend on it).
  void plan(const ObjectRefs& objects, const DetectOptions& opt, PairLoop& loop);

 private:
  SweepScratch sweep_;
  std::vector<int> needs_, tiles_;
  void reset(std::size_t i, const ObjectRefs& objects, int tile);
  std::vector<SelfTree> self_trees_;  // per object asking for self-collision (self_overlap_pairs())
  // `spread`: the pair's traversal over the loop's lanes (a large mesh, planned after the pair
  // loop); null: on the calling lane.
  void plan_self(const Mesh& mesh, const DetectOptions& opt, PairPlan& p, SelfTree& tree, PairLoop* spread = nullptr);
  std::vector<std::size_t> spread_self_;  // plan(): the self pairs planned after the pair loop
  std::vector<BvhNodePair> self_split_;
  BvhSplitScratch self_split_scratch_;
  void plan_box(const ObjectRefs& objects, const DetectOptions& opt, PairPlan& p);
  void share_budget(const DetectOptions& opt);
  void route(const DetectOptions& opt);
};

// View `v` (along `frame`) of planned pair `pair_index` as a job: its padded ROI view, each
// object's triangles in it (kept triangles only under Cull::contact; the pad follows the view's
// texel size) into tris_a and tris_b, the options' fields. `epsilon` is set from view 0 (the
// options', or one texel). job.triangles are left to the caller (the vectors may still move).
// Returns each object's nearest depth in the view (the farther object is peeled first).
std::pair<double, double> make_view_job(const ObjectRefs& objects, const FramePlan& frame_plan, std::size_t pair_index,
                                        const DetectOptions& opt, const ViewFrame& frame, int v, double& epsilon,
                                        std::vector<std::uint32_t>& tris_a, std::vector<std::uint32_t>& tris_b,
                                        PeelJob& job);

}  // namespace peelcd::detail
