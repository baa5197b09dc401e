#pragma once
// The World's state (internal to peelcd_core): its bodies and a frame's scratch. world.cpp holds
// the API (bodies added, moved, removed); world_frame.cpp a frame (World::collide()).

#include "peelcd/core/world/world.h"
#include "route_timer.h"
#include "peelcd/core/image/planner.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/image/image_stage.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/worker_pool.h"
#include "../exact/apart_block.h"

#include <atomic>
#include <chrono>
#include <map>
#include <unordered_map>
#include <optional>
#include <string>
#include <thread>

namespace peelcd {
namespace world_detail {

// What a task does: traverse two trees from a node pair, scan two small world meshes (one culling
// round and a sweep, as the frame API's exact path), or traverse a body's tree against itself.
enum class TaskKind : std::uint8_t { nodes, small_pair, self };

// A rigid body with fewer triangles than this may be copied into world space for a frame (its
// vertices transformed, a copy of its tree refitted over them): O(its size), and its boxes are
// then exact world boxes, where boxes carried through a rotation grow (a small ball's tree seen
// from a neighbour's frame overlaps far more of it). It is, when it stands still (the copy
// serves later frames) or has kCopyPairs pairs or more. Larger rigid bodies are never touched
// beyond what the traversal reaches.
// 8,192 puts test1's 4,512-triangle balls in world space: boxes carried through a pose cost a
// transform per node pair, which their traversal pays more than their copy.
constexpr std::size_t kWorldFrameTriangles = 8192;
// A moving small rigid body paired with this many bodies or more is copied into world space;
// with fewer it is traversed through its pose (World::Impl::copy_paired()).
// 4: a body in one to three pairs (test2's falling objects) is faster traversed through its
// pose; one in about five (a ball of the 400-ball pile) pays for its copy twice over.
constexpr std::size_t kCopyPairs = 4;

// A rigid body whose pose's linear part has a condition number (largest over smallest singular
// value; estimated, Body::set_pose()) above this is moved into world space every frame it is paired, whatever its size: the
// posed traversal composes one pose's inverse with the other, whose error grows with the
// condition number (about cond * 2^-53 relative), and its boxes are grown by 1e-9 of their
// magnitudes; 1e4 keeps that error 500 times under the growth. (Anisotropic poses with
// conditions 1e11 and more missed contacts through their pose; in world space a body's
// triangles are its world mesh's, which is what the exact reference tests.)
constexpr double kPosedConditionLimit = 1e4;

// A pair of bodies with fewer triangles than this between them is one task, whatever the lanes
// (a split's walk and tasks cost more than a second lane saves on it).
constexpr std::size_t kSplitTriangles = 32768;
// Fewer pairs than this many a lane split their traversals into node pairs for the lanes to
// share, kSplitNodePairsPerLane a lane (the contact region of two crossing spheres sits in few of
// them: rigid 1.3M spheres at 2 threads 0.61 of one); more pairs share the lanes as they are (a
// split costs a breadth-first walk and its tasks).
constexpr std::size_t kSplitPairsPerLane = 8;
constexpr std::size_t kSplitNodePairsPerLane = 32;
// A deforming body with this many triangles or more is refitted in one chunk per lane (under it,
// the chunks cost more than the lanes save).
constexpr std::size_t kSplitRefitTriangles = 32768;
// Such a body's tree has its nodes refitted in about this many subtrees (Bvh::plan_parts),
// whatever the lanes (the waving 1.3M-triangle spheres' nodes took 0.6 ms a body on one lane
// after their leaves' 0.8 ms on eight: peelcd_world_loop --wave 570 --model 8).
constexpr std::size_t kRefitParts = 64;

struct Body {
  bool alive = false;
  bool is_rigid = false;
  std::string name;
  std::shared_ptr<const Mesh> shape;  // rigid
  Mesh mesh;                          // deforming: world space
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  bool ill_conditioned = false;  // the pose's condition is over kPosedConditionLimit: world space
  // The condition estimated as |L|_F |L^-1|_F (at least the 2-norm condition, at most 3x it;
  // 3 for a rotation): a few dozen flops, paid by every set_pose() of a moving body.
  void set_pose(const Eigen::Affine3d& p) {
    pose = p;
    const Eigen::Matrix3d linear = p.linear();
    ill_conditioned = !(linear.norm() * linear.inverse().norm() <= kPosedConditionLimit);
  }
  Bvh tree;
  // A small rigid body this frame: its world-space mesh, and its tree refitted over it when a
  // pair with a large body traverses it (world_tree_fresh).
  // The copy, its box and its tree are kept while the pose stays (a static body is copied once);
  // `moved`: copied again this frame.
  bool world_frame = false;
  Mesh world_copy;
  Aabb world_copy_box;
  Bvh world_tree;
  bool world_tree_fresh = false;
  bool copy_valid = false, moved = false;
  Eigen::Affine3d copied_pose = Eigen::Affine3d::Identity();
  bool still = false;  // the pose is the last frame's (a copy made now will serve the next frames)
  Eigen::Affine3d last_pose = Eigen::Affine3d::Identity();
  // Deforming: its tree is refitted whole at the next collide() (set_vertices, many moved
  // vertices), every such body's triangles split over the frame's lanes.
  bool refit_pending = false;
  // Deforming, this frame: its pending refit put off (World::Impl::defer_refits()): every pair
  // of it is drawn by the resident image route, which needs its box (loaded_box) but not its
  // tree. The refit stays pending (done by a later frame that needs the tree, World::tree(), or
  // a view the stage cannot resolve).
  bool refit_deferred = false;
  bool tree_current() const { return !refit_pending; }
  // Deforming: set_vertices() checked, rounded (Bvh::load_vertices; see points_rounded) and
  // copied the vertices in one pass: the pending refit starts from those floats (`loaded_box`:
  // the exact box of the used vertices). The copy goes to `spare_vertices`, swapped with the
  // mesh's once all are checked (a refused call leaves the body as it was).
  bool points_loaded = false;
  // With points_loaded: the load rounded them into the tree too (else the refit rounds them).
  bool points_rounded = false;
  Aabb loaded_box;
  std::vector<Vec3> spare_vertices;
  // Deforming: the triangles using each vertex (CSR), built on the first move_vertices().
  std::vector<std::uint32_t> vertex_first, vertex_tris;
  // Self-collision (World::set_self): the vertex representatives of the adjacency in use
  // (rep_valid: for this topology and `rep_adjacency`); a rigid body's self contacts, in its
  // shape's frame, found once per shape (a rigid motion changes none of them).
  bool self = false;
  bool rep_valid = false;
  SelfAdjacency rep_adjacency = SelfAdjacency::index;
  std::vector<std::uint32_t> rep;
  bool self_cached = false;
  ContactDetail self_detail = ContactDetail::segments;  // what the cached contacts hold
  std::vector<Contact> self_contacts;
  void topology_changed() {
    rep_valid = false;
    self_cached = false;
    topology.reset();
  }
  // Deforming: what the GL stage keys this body's resident triangles by (MovingMesh::topology);
  // made when the image route first draws the body, dropped when its triangles change.
  std::shared_ptr<const char> topology;
  const std::vector<std::uint32_t>& representatives(SelfAdjacency adjacency) {
    // By position on a deforming body: the positions of this frame.
    if (!rep_valid || rep_adjacency != adjacency || (adjacency == SelfAdjacency::position && !is_rigid)) {
      vertex_representatives(local(), adjacency, rep);
      rep_adjacency = adjacency;
      rep_valid = true;
      self_cached = false;
    }
    return rep;
  }

  const Mesh& local() const { return is_rigid ? *shape : mesh; }
  Vec3 world(std::uint32_t v) const {
    return !is_rigid ? mesh.vertices[v] : world_frame ? world_copy.vertices[v] : Vec3(pose * shape->vertices[v]);
  }
  // The array world() reads (a posed rigid body's: its shape's, before the pose).
  const Vec3* world_vertices() const {
    return !is_rigid ? mesh.vertices.data() : world_frame ? world_copy.vertices.data() : shape->vertices.data();
  }
  // Small (under kWorldFrameTriangles) and in world space this frame: a pair of two such bodies,
  // one of them a rigid body that moved and in no other pair, is tested as the frame API tests
  // it (one culling round over both meshes, a sweep of the kept triangles' boxes): that scan
  // costs less than refitting the moved body's world-space tree for one pair. A moved body in
  // several pairs refits its tree once for all of them (cheaper than scanning every pair).
  // Otherwise the trees are current (deforming bodies' refitted, a still rigid body's world tree
  // kept): their traversal costs less than the scan.
  bool small() const { return local().triangles.size() < kWorldFrameTriangles; }
  const Mesh* world_mesh() const { return !is_rigid ? &mesh : world_frame && copy_valid ? &world_copy : nullptr; }
  // The tree the traversals use and the pose it is posed by: a small rigid body's world copy
  // (identity), else its own.
  const Bvh& frame_tree() const { return world_frame ? world_tree : tree; }
  Bvh& frame_tree() { return world_frame ? world_tree : tree; }
  Eigen::Affine3d frame_pose() const { return world_frame ? Eigen::Affine3d::Identity() : pose; }
  // Small rigid bodies: into world space for this frame. enter_frame() only notes whether the
  // copy is current (`moved`: the pose changed since it was made); World::Impl::copy_paired()
  // makes it for the bodies that need it (ensure_copy()) or leaves a moving body with fewer than
  // kCopyPairs pairs in its own frame (posed_this_frame()); the tree only when a traversal needs it
  // (ensure_world_tree()).
  void enter_frame() {
    world_frame = is_rigid && (shape->triangles.size() < kWorldFrameTriangles || ill_conditioned);
    moved = false;
    if (!world_frame) {
      copy_valid = world_tree_fresh = false;
      return;
    }
    still = last_pose.matrix() == pose.matrix();
    last_pose = pose;
    if (copy_valid && copied_pose.matrix() == pose.matrix()) return;  // unchanged since the last copy
    world_tree_fresh = false;
    copy_valid = false;
    moved = true;
  }
  // Returns the vertices transformed (0: the copy was current).
  std::size_t ensure_copy() {
    if (!world_frame || copy_valid) return 0;
    if (world_copy.triangles.size() != shape->triangles.size()) world_copy.triangles = shape->triangles;
    world_copy.vertices.resize(shape->vertices.size());
    Aabb box;  // the copy's box, in the same pass (as bounds(world_copy))
    for (std::size_t v = 0; v < world_copy.vertices.size(); ++v) {
      const Vec3 p = pose * shape->vertices[v];
      world_copy.vertices[v] = p;
      box.lo = box.lo.cwiseMin(p);
      box.hi = box.hi.cwiseMax(p);
    }
    world_copy_box = world_copy.triangles.empty() ? Aabb{} : box;
    copied_pose = pose;
    copy_valid = true;
    return world_copy.vertices.size();
  }
  // This frame in its own frame, posed (a moved small body in one pair: a traversal through its
  // pose costs less than copying it; its copy stays stale).
  void posed_this_frame() { world_frame = false; }
  void ensure_world_tree() {
    if (!world_frame || world_tree_fresh) return;
    // The shape's tree, its boxes refitted over the copy (a rigid motion keeps its grouping: no
    // build).
    if (world_tree.triangles() != shape->triangles.size() || world_tree.empty() != tree.empty()) world_tree = tree;
    world_tree.refit(world_copy.vertices, world_copy.triangles);
    // Its wide view too: the copy is refitted only for traversals, which cover much of a small
    // body's tree (the 400-ball pile's frame: 0.94x the instructions of the binary traversal).
    world_tree.sync_wide();
    world_tree_fresh = true;
  }
  // The world box: the copy's (exact) where it is current, else the root box moved by the pose.
  Aabb world_box() const {
    if (world_frame && copy_valid) return world_copy_box;
    if (!is_rigid && refit_pending && points_loaded) return loaded_box;  // (the refit's root box)
    const Aabb b = tree.box();
    if (!is_rigid || b.empty()) return b;
    // The root box moved by the pose, grown as the traversal grows its boxes.
    return BvhRelation::moved(b, pose.linear(), pose.linear().cwiseAbs(), pose.translation(),
                              pose.translation().cwiseAbs().maxCoeff());
  }
};

inline std::string label_of(const std::string& name, BodyId id) {
  return "body " + std::to_string(id) + (name.empty() ? "" : " '" + name + "'");
}

// One piece of a pair's traversal: a node pair, the candidates found under it, then (exact
// path) the contacts among them, in candidate order.
// (A cache line or more each: two lanes work on neighbouring tasks, and each writes its own.)
struct alignas(64) Task {
  std::size_t pair = 0;
  TaskKind kind = TaskKind::nodes;
  BvhNodePair start;  // TaskKind::nodes: the node pair it starts from
  std::vector<std::uint64_t> candidates;
  std::vector<Contact> contacts;
  std::size_t visited = 0, transformed = 0;
  std::size_t tested = 0;  // a self task's couples given to the exact test
};

// A node pair of two rigid bodies' trees and its world boxes (rigid_contact_region()).
struct RegionEntry {
  std::uint32_t i = 0, j = 0;
  Aabb a, b, meet;
};
struct RegionScratch {
  std::vector<RegionEntry> level, next;
};

}  // namespace world_detail

using namespace world_detail;
using exact_detail::ApartBlock;

struct World::Impl {
  std::atomic<std::thread::id> owner{};  // the thread inside a frame or a change (ExclusiveUse)
  std::shared_ptr<ImageStage> stage;
  std::unique_ptr<Detector> detector;  // made on the first pair routed to the image stage
  std::vector<Body> bodies;
  std::size_t alive = 0;
  WorldStats stats;
  FrameResult result;
  // Frame scratch.
  std::vector<Aabb> boxes;
  std::vector<BodyId> ids;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  SweepScratch sweep;  // find_pairs()
  std::vector<Task> tasks;
  std::vector<BvhNodePair> split;
  BvhSplitScratch split_scratch;  // plan_tasks()' bvh_split()
  // The split tasks' costs in the last frame, by split_key() (sorted), for order_split().
  std::vector<std::pair<std::uint64_t, std::uint32_t>> split_costs, split_costs_next;
  std::vector<std::pair<std::uint32_t, BvhNodePair>> split_order;
  std::vector<std::size_t> to_copy;     // copy_paired(): the bodies (ids) copied this frame
  std::vector<char> drawn_only;         // copy_paired(): bodies (ids) whose pairs the resident route draws, all
  std::vector<std::uint32_t> pairs_of;  // plan_tasks(): per body of the frame (ids), its pairs with others
  // Per lane, each on its own cache line (a traversal writes its stack's size at every push).
  template <class T>
  struct alignas(64) LaneStack {
    std::vector<T> v;
  };
  std::vector<LaneStack<BvhStackEntry>> stacks;
  std::vector<LaneStack<BvhNodePair>> self_stacks;
  struct LaneScratch {
    ContactCull cull;
    BoxScratch boxes;
    std::vector<std::uint64_t> sorted;
    ContactSortScratch contacts;  // a pair's contacts sorted (gather_contacts())
    ApartBlock apart;             // the exact path's couples, a block at a time (test_task())
    std::vector<std::uint64_t> pcs_keys;  // resident_image_pairs(): a pair's PCS as keys
    std::vector<IdPair> pcs;              // ... as pairs of IDs, for the ID maps
    IdMap map_a, map_b;
    std::vector<double> edges;  // median_edge()'s
  };
  std::vector<std::unique_ptr<LaneScratch>> lane_scratch;  // per lane: the small pairs' scan
  std::vector<std::uint64_t> candidates;
  std::vector<std::size_t> first_task;  // pair p's tasks: [first_task[p], first_task[p + 1])
  std::vector<char> to_image;           // pair p goes to the image stage
  std::vector<Aabb> body_boxes;         // per BodyId, this frame's world box
  RelateLanes relate_lanes;              // relate(): the pairs related over the lanes
  std::map<std::size_t, Mesh> world_meshes;  // large rigid bodies' world meshes a relation needed
  std::unique_ptr<WorkerPool> pool;

  Body& body(BodyId id, const char* what) {
    if (id >= bodies.size() || !bodies[id].alive)
      throw std::invalid_argument(std::string("peelcd::World::") + what + "(): no body " + std::to_string(id));
    return bodies[id];
  }
  const Body& body(BodyId id) const {
    if (id >= bodies.size() || !bodies[id].alive)
      throw std::invalid_argument("peelcd::World: no body " + std::to_string(id));
    return bodies[id];
  }
  // Named bodies by name (World::find); a name is one body's while it lives.
  std::unordered_map<std::string, BodyId> names;

  BodyId add(Body b) {
    const BodyId id = BodyId(bodies.size());
    if (!b.name.empty() && names.count(b.name))
      throw std::invalid_argument("peelcd::World: " + label_of(b.name, id) + ": the name is taken by body " +
                                  std::to_string(names.at(b.name)) + " (names identify bodies: give each its own)");
    b.alive = true;
    b.tree.build(b.local().vertices, b.local().triangles);
    ++stats.builds;
    ++alive;
    if (!b.name.empty()) names.emplace(b.name, id);
    bodies.push_back(std::move(b));
    return id;
  }

  // The last frame's lanes: World::set_vertices() checks and copies a large body's vertices
  // over them.
  unsigned frame_lanes = 1;
  ContactDetail detail = ContactDetail::segments;  // this frame's DetectOptions::contacts
  std::size_t vertex_parts(std::size_t n) const;  // the parts set_vertices() splits n vertices in
  std::vector<std::size_t> part_bad;  // set_vertices(): each part's first bad vertex and box
  std::vector<Aabb> part_boxes;
  // fn(k) for k in [0, parts), one part a lane (parts <= the pool's lanes).
  template <class Fn>
  void in_parts(std::size_t parts, Fn&& fn) {
    parallel("parts", parts, unsigned(parts), [&](std::size_t k, unsigned) { fn(k); });
  }
  unsigned lanes_for(const DetectOptions& opt) {
    if (model_lanes) return model_lanes;  // planned for them, run here (model_loop())
    if (opt.threads == 1) return 1;
    if (!pool || (opt.threads != 0 && pool->lanes() != opt.threads)) pool = std::make_unique<WorkerPool>(opt.threads);
    return pool->lanes();
  }
  // body(i, lane) for i in [0, n), spread over the pool's lanes when there are several. `step`
  // names the loop for the lane model.
  template <class Fn>
  void parallel(const char* step, std::size_t n, unsigned lanes, Fn&& fn) {
    if (stacks.size() < lanes) stacks.resize(lanes);
    if (self_stacks.size() < lanes) self_stacks.resize(lanes);
    while (lane_scratch.size() < lanes) lane_scratch.push_back(std::make_unique<LaneScratch>());
    if (n <= 1) {  // (one item: on the calling thread, whatever the lanes)
      for (std::size_t i = 0; i < n; ++i) fn(i, 0u);
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    if (model_lanes && lanes > 1) {
      model_start();
      model_items.resize(n);
      auto t = t0;
      for (std::size_t i = 0; i < n; ++i) {
        fn(i, unsigned(i * lanes / n));  // (its lane's range: as for_each starts it)
        const auto u = std::chrono::steady_clock::now();
        model_items[i] = std::chrono::duration<double, std::milli>(u - t).count();
        t = u;
      }
      model_loop(step, lanes);
      model_loops.back().wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    } else if (lanes <= 1) {
      for (std::size_t i = 0; i < n; ++i) fn(i, 0u);
    } else {
      pool->for_each(n, fn);  // (a task or body keeps its lane from loop to loop and frame to frame)
    }
    loops_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  // The lane model (World::model_lanes): 0 off, else the lanes every frame is planned for; each
  // loop's item times (model_items) replayed on them as WorkerPool::for_each would run them.
  unsigned model_lanes = 0;
  static constexpr unsigned kMaxModelLanes = 256;
  std::vector<double> model_items;
  std::vector<LaneLoop> model_loops;  // since the last collide() returned (World::lane_loops())
  bool model_done = true;             // a collide() returned since the last loop: model_loops is past
  std::size_t model_first = 0;        // this collide()'s first loop in model_loops
  void model_start() {
    if (model_done) model_loops.clear(), model_done = false;
  }
  void model_loop(const char* step, unsigned lanes);
  double loops_ms = 0.0;  // this frame's time in parallel()'s loops (WorldStats::loops_ms)

  // The deferred whole-tree refits (World::set_vertices, many moved vertices): every pending
  // body's triangle boxes in chunks over the lanes (a large body split in as many chunks as
  // lanes), then each body's nodes.
  struct RefitChunk {  // a part of a body's refit: a range of its vertices and one of its leaves
    std::size_t body;    // its entry in refit_bodies
    std::size_t vertex_begin, vertex_end, leaf_begin, leaf_end;
    Aabb exact;          // the exact box of its vertices the triangles use
  };
  struct RefitPart {  // a subtree of a body's tree (Bvh::plan_parts)
    std::size_t body, part;
  };
  struct RefitBody {
    Body* body;
    std::size_t first, last;  // its chunks in refit_chunks
    bool rebuilt;             // its tree grew past kBvhRebuildGrowth: built again
    std::size_t parts = 0;    // then its build's subtrees (Bvh::plan_build)
  };
  std::vector<RefitChunk> refit_chunks;
  std::vector<RefitBody> refit_bodies;
  std::vector<RefitPart> refit_parts;
  std::vector<std::size_t> refit_grown;  // refit_bodies whose trees grew past kBvhRebuildGrowth
  std::vector<RefitPart> build_parts;     // their builds' subtrees (Bvh::plan_build), over the lanes
  // The pending refits of the bodies that need their trees this frame (`all`: every body; else
  // those not refit_deferred).
  void refit_pending(unsigned lanes, bool all = true);
  void rebuild_grown(unsigned lanes);
  bool may_defer_refit(const Body& b, const DetectOptions& opt) const;
  void defer_refits(unsigned lanes);
  // One body's pending refit now (World::tree() asked for it between frames).
  void refit_now(Body& b) {
    b.refit_deferred = false;
    if (!b.refit_pending) return;
    b.tree.refit(b.mesh.vertices, b.mesh.triangles);
    b.refit_pending = b.points_loaded = false;
    ++stats.full_refits;
    stats.builds += b.tree.rebuild_if_grown(b.mesh.vertices, b.mesh.triangles);
  }

  void collide(const DetectOptions& opt, FrameResult& out);
  void collide_frame(const DetectOptions& opt, FrameResult& out);  // one frame on opt's stage
  // Stage::automatic on the resident route of a GPU: the routes timed (route_timer.h).
  std::optional<bool> time_routes_opt;  // World::time_routes()
  bool timing_routes(const DetectOptions& opt) const;
  RouteTimer route_timer;
  std::optional<bool> routes_timed;  // the last frame's routes were timed (none before a frame)
  DetectOptions image_opt;  // the frame's options with Stage::image (its storage kept)
  // The steps of collide(), in order.
  void find_pairs(const DetectOptions& opt, unsigned lanes);
  void count_pairs();
  void copy_paired(const DetectOptions& opt, unsigned lanes);
  std::size_t plan_tasks(unsigned lanes);
  void order_split(std::size_t ida, std::size_t idb, unsigned lanes);
  void keep_split_costs(std::size_t used);
  void keep_wide_views();
  void traverse(std::size_t used, unsigned lanes);
  void traverse_task(std::size_t k, unsigned lane);
  void route_pairs(const DetectOptions& opt, std::size_t used, FrameResult& out);
  void test_candidates(const DetectOptions& opt, std::size_t used, unsigned lanes);
  void test_task(const Body& a, const Body& b, const DetectOptions& opt, Task& t, ApartBlock& block);
  template <bool kKeep>  // a triangle's corners kept for the couples that follow (test_task())
  void test_task_as(const Body& a, const Body& b, const DetectOptions& opt, Task& t, ApartBlock& block);
  void gather_contacts(FrameResult& out);
  void relate(const DetectOptions& opt, FrameResult& out);
  // A self pair's contacts: its tasks' (in the body's frame), cached for a rigid body, moved to
  // world space.
  void self_pair(Body& a, std::size_t first, std::size_t last, PairResult& r, ContactSortScratch& scratch);
  // The image-routed pairs (or pair `only` alone) through the Detector in one frame.
  static constexpr std::size_t kAllPairs = std::size_t(-1);
  void image_pairs(const DetectOptions& opt, FrameResult& out, std::size_t only = kAllPairs);
  std::optional<bool> batch_pairs;  // World::batch_image_pairs()
  bool batched_image() const {
    if (batch_pairs) return *batch_pairs;
    return stage->prefers_batches();
  }
  // The image-routed pairs' objects (two a pair), their triangles' indices in the bodies, the
  // pair each came from, and the object pairs the Detector is asked for.
  std::vector<Object> image_objects;
  std::vector<std::vector<std::uint32_t>> image_kept;
  std::vector<std::size_t> image_of;
  std::vector<std::pair<std::size_t, std::size_t>> image_only;

  // The image-routed pairs of two bodies, rigid or deforming, batched (resident_image_pairs()):
  // a rigid body drawn from its shape, resident on the stage (uploaded once), by its pose; a
  // deforming one from its triangles, resident (uploaded once per topology), and its vertices
  // (uploaded once a frame); the views' PCS become the pair's candidates, tested on the exact
  // path's tasks. No triangle is copied.
  void resident_image_pairs(const DetectOptions& opt, FrameResult& out);
  bool resident_route(const DetectOptions& opt) const;
  bool resident_pair(std::size_t p) const;
  void mark_untraversed(const DetectOptions& opt);
  double median_edge(const Body& b, std::vector<double>& edges);  // (a deforming body: on any lane; a rigid one: on the calling thread)
  Aabb contact_region(std::size_t p, const Aabb& roi, RegionScratch& scratch) const;
  std::vector<Aabb> resident_regions;           // per resident pair: where its bodies can meet
  std::vector<RegionScratch> region_stacks;  // per lane
  std::vector<char> untraversed;                // pair p's traversal skipped (empty: none)
  std::vector<char> peeled_resident;            // pair p: its candidates are its views' PCS
  std::vector<std::size_t> resident_pairs;      // this frame's, in pair order
  std::vector<Object> resident_objects;         // two a pair: shape and pose, or moving mesh
  std::vector<PeelJob> resident_jobs;
  std::vector<std::size_t> resident_job_first;  // resident pair i's jobs: [first[i], first[i + 1])
  std::vector<PeelResult> resident_peeled;
  std::vector<int> resident_needs, resident_tiles;
  std::vector<double> frame_edges;  // per body of the frame (ids): its median edge, or -1 (not yet)
  std::vector<double> edge_scratch;  // median_edge()'s, on the calling thread
  std::vector<std::size_t> edge_bodies;  // resident_image_pairs(): deforming bodies (ids) whose edges are measured
  std::vector<char> resident_exhaustive;  // per resident pair: a view the stage could not resolve
  struct ShapeEdge {
    std::weak_ptr<const Mesh> owner;
    double edge = 0.0;
  };
  std::unordered_map<const Mesh*, ShapeEdge> shape_edges;  // a shape's median edge (tiles by need)
};


}  // namespace peelcd
