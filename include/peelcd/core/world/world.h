#pragma once
// Persistent objects: the bodies of a scene, kept from frame to frame, so that a frame's cost
// follows the contact, not the meshes.
//
//   World world(stage);                           // any image stage; none: the exact CPU path
//   BodyId ball = world.add_rigid(shape, pose);   // a rigid body: its shape and a pose
//   BodyId cloth = world.add_deforming(mesh);     // a deforming body: world-space vertices
//   ... each frame:
//   world.set_pose(ball, pose);                   // a rigid body moves by its pose alone
//   world.move_vertices(cloth, changed, where);   // or set_vertices(cloth, all) / set_mesh (fracture)
//   const FrameResult& r = world.collide(options);
//
// Each body keeps a BVH of its triangles (peelcd/core/exact/bvh.h) in its own frame: a rigid body's
// is built once from its shape and never touched again; a deforming body's is refitted where its
// vertices moved (only the changed triangles' leaves and ancestors when it says which changed),
// rebuilt when its topology changes (set_mesh). A frame then reads only what lies near contact:
// the bodies' boxes (the broad phase: each tree's root box, moved by the pose), and per pair of
// overlapping boxes the node pairs of the two trees that overlap, down to the couples of
// triangles whose boxes overlap (the candidates, B's boxes seen from A's frame, grown by a
// relative 1e-9 against rounding). A large rigid body's world vertices are computed (pose *
// vertex) only for the candidates' corners; far triangles are never read. A small rigid body
// (under kWorldFrameTriangles, 8,192 triangles) is moved into world space whole each frame instead (its vertices
// transformed, a copy of its tree refitted: microseconds), since boxes carried through a
// rotation are looser and a small body gains more from exact world boxes than it pays; a pair
// of two such small world-space bodies is scanned as the frame API's exact path scans it (one
// culling round, a sweep of the kept triangles' boxes), cheaper than two small trees.
//
// Each pair goes to the exact CPU path (every candidate through the exact triangle test,
// peelcd/core/exact/narrow_phase.h), or to the image stage (Stage::image, or when the router predicts
// it cheaper): then the candidates' triangles, in world space, are peeled as two objects through
// a Detector on the World's stage, and its contacts mapped back to the bodies' triangles.
// Results are exact either way: a contact is reported iff the two triangles share a point of
// their world-space corners (the same doubles whichever path tested them).
//
// With DetectOptions::threads > 1 the object pairs and, inside a pair, the two trees' node pairs
// are spread over a pool of threads. One thread calls a World at a time: every public function,
// readers included, takes a guard (peelcd/core/exclusive_use.h), so a second thread that enters
// while another is inside gets std::logic_error and the first thread's call is unaffected. What
// a reference returned by collide(options), name() or mesh() refers to belongs to the World: it
// stays valid until the caller's next change or frame; a caller that shares a World between
// threads under its own lock copies it (or uses collide(options, out)) before unlocking.
#include "peelcd/core/exact/bvh.h"
#include "peelcd/core/image/detector.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace peelcd {

using BodyId = std::uint32_t;

// What the World did, cumulative since it was made (the counters a test or benchmark reads).
struct WorldStats {
  std::size_t builds = 0;           // trees built (add_*, set_mesh)
  std::size_t full_refits = 0;      // whole-tree refits done (set_vertices, many moved vertices)
  std::size_t partial_refits = 0;   // refits of the changed triangles' paths only
  std::size_t node_pairs = 0;       // node pairs visited by the traversals, last frame (a 4-wide traversal
                                    // counts pairs of wide nodes and leaves: fewer for the same couples)
  std::size_t candidates = 0;       // triangle couples whose boxes overlap, last frame
  std::size_t vertices_transformed = 0;  // rigid bodies' world vertices computed, last frame
  // The last frame's time (ms) in its steps' loops over pairs, tasks or bodies, which spread
  // over the lanes when threads > 1, and in the steps between them, which run on the calling
  // thread alone (the whole frame: one_lane_ms + loops_ms, the image stage's work included in
  // one_lane_ms). With T threads a frame takes at least one_lane_ms + loops_ms / T.
  double loops_ms = 0.0, one_lane_ms = 0.0;
  // With the lane model on (World::model_lanes(L)): the last frame as L lanes would take it, from
  // its items' times on one thread: one_lane_ms + each loop's span (LaneLoop::span_ms). A bound
  // from the work's balance alone (no wake-ups, no memory shared by the lanes). 0 when off.
  double model_ms = 0.0;
  // Routes timed (World::time_routes()): frames whose pairs all went to the image route, and
  // whether the last frame belonged to a comparison of the two routes rather than to a choice.
  std::size_t image_route_frames = 0;
  bool route_comparing = false;
};

// A loop of the last frame over pairs, tasks or bodies as the lane model timed it
// (World::model_lanes()): its items' summed and longest times on one thread, and its span: the
// time L lanes take to run them in the order WorkerPool::for_each gives them (contiguous ranges,
// then the others' last items), each item taking its measured time.
struct LaneLoop {
  const char* step = "";  // the frame's step ("traverse", "test", ...)
  std::size_t items = 0;
  double total_ms = 0.0, longest_ms = 0.0, span_ms = 0.0;
  double wall_ms = 0.0;  // the loop on this thread, its clocks and replay included
};

class World {
 public:
  // `stage`: the image stage pairs routed to it are peeled on (nullptr: the CPU image stage).
  explicit World(std::shared_ptr<ImageStage> stage = nullptr);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // A rigid body: world = pose * shape. The shape is shared (several bodies may hold one), never
  // copied. Throws std::invalid_argument naming the body (`name`, else its id) and the problem.
  BodyId add_rigid(std::shared_ptr<const Mesh> shape, const Eigen::Affine3d& pose, std::string name = {});
  // A deforming body: its world-space mesh, updated by set_vertices / move_vertices / set_mesh.
  BodyId add_deforming(Mesh mesh, std::string name = {});
  void remove(BodyId body);

  void set_pose(BodyId body, const Eigen::Affine3d& pose);  // rigid bodies
  // Every vertex of a deforming body moved (same count): its tree refitted whole at the next
  // collide() (every such body's refit split over the frame's threads), or, where that frame's
  // image route draws every pair of the body from the GPU (Stage::image, batched), at the
  // first frame or query (tree()) that needs the tree. The const& overload
  // copies into the body's own storage (no allocation after the first frame); the rvalue
  // overload takes the vector over.
  void set_vertices(BodyId body, const std::vector<Vec3>& vertices);
  void set_vertices(BodyId body, std::vector<Vec3>&& vertices);
  // Only these vertices moved (indices into the body's vertices, `positions` parallel to them):
  // only the triangles using them are refitted.
  void move_vertices(BodyId body, const std::vector<std::uint32_t>& indices, const std::vector<Vec3>& positions);
  // A new mesh for the body (fracture, remeshing): its tree rebuilt. A rigid body's becomes its
  // new shape (the pose kept).
  void set_mesh(BodyId body, Mesh mesh);
  // A rigid body's new shape, shared (its tree rebuilt; the pose kept).
  void set_shape(BodyId body, std::shared_ptr<const Mesh> shape);

  // Self-collision of the body (docs/design.md, "Self-collision"; DetectOptions::self asks it
  // for every body): its own tree traversed against itself, adjacent couples dropped, every
  // remaining couple tested exactly (the World's self pairs take the exact path). A rigid
  // body's self pairs are found once per shape (a rigid motion changes none) and moved by its
  // pose; a deforming body's each frame, over its refitted tree.
  void set_self(BodyId body, bool self);
  bool self(BodyId body) const;

  bool contains(BodyId body) const;
  std::size_t size() const;               // bodies held
  const std::string& name(BodyId body) const;
  // The living body named `name` (names are unique: add_rigid / add_deforming refuse a name a
  // living body has), or none.
  std::optional<BodyId> find(const std::string& name) const;
  bool rigid(BodyId body) const;
  // The body's mesh in its own frame (a rigid body's shape; a deforming body's world mesh).
  const Mesh& mesh(BodyId body) const;
  // The body's world-space mesh, computed (for rigid bodies, O(vertices): for tools and tests).
  Mesh world_mesh(BodyId body) const;
  const Bvh& tree(BodyId body) const;

  // One frame: every pair of bodies whose boxes overlap, as Detector::detect reports it
  // (FrameResult::pairs' object_a / object_b are BodyIds, a < b; contacts sorted). Options are
  // checked (validate_options); Stage::exact never touches the image stage.
  const FrameResult& collide(const DetectOptions& options);
  void collide(const DetectOptions& options, FrameResult& out);

  const WorldStats& stats() const;
  ImageStage& stage();

  // Measurement (peelcd_world_loop --model L): with lanes >= 2, each frame is planned for `lanes`
  // lanes (as DetectOptions::threads = lanes plans it) but runs on the calling thread, each item
  // of its loops timed, and WorldStats::model_ms and lane_loops() say what `lanes` lanes would
  // take by the work's balance: how much of a frame's scaling its uneven items cost, measurable
  // on a machine with fewer cores. 0 or 1: off (the default). The frame's results are the same.
  void model_lanes(unsigned lanes);
  // The loops under the lane model since the collide() before the last one returned, in order:
  // set_vertices()'s splits of a large body's vertices, then the last frame's (empty when off).
  const std::vector<LaneLoop>& lane_loops() const;

  // The pairs routed to the image stage go to it together, in one frame of the stage (one batch
  // of views and a sync, where one at a time costs a sync a pair: the faster on a GPU), or one
  // at a time (each pair's views alone: the faster where GL runs on the CPU). Unset: together on
  // a GPU, or where a software renderer was asked for the GPU's resolve (GlOptions::resolve gpu:
  // the production path), one at a time elsewhere (ImageStage::prefers_batches(): llvmpipe,
  // softpipe, swrast, the CPU stage). Together, the pairs of two rigid bodies are drawn from their
  // shapes, resident on the stage (docs/backends.md).
  void batch_image_pairs(std::optional<bool> together);

  // Stage::automatic where the image route is the resident one (batched, conservative, no
  // margin): the router's per-pair models decide after the traversal, which the image route
  // would skip, so they cannot see what it saves. With routes timed, the World runs its frames
  // on the routed path or with every pair on the image route (as Stage::image), times each over
  // a few frames of its own, keeps the faster and times the other again now and then
  // (docs/backends.md, "The World times its routes"). The contacts are the same either way;
  // the pairs' route, candidates and predictions follow the route taken. Unset: timed where
  // the stage's work runs on a GPU (not ImageStage::runs_on_cpu()), not elsewhere.
  void time_routes(std::optional<bool> timed);
  // The next frame belongs to a comparison of the routes (a route being timed), not to a
  // choice: true from the start until the first choice; false where routes are not timed
  // (time_routes(false), or unset on a stage that runs on the CPU) or the last frame's options
  // did not time them (a margin, point sampling, views one at a time, a forced stage).
  bool comparing_routes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Brings `world` to a frame given as the frame API's objects (peelcd/core/mesh.h), body
// `bodies[i]` for objects[i] (added on the first call: `bodies` empty): a rigid object moves
// its body by its pose (its world mesh is not read; a new shape pointer is a set_mesh), a
// deforming one replaces its body's vertices (a new topology: set_mesh). A frame of world meshes
// costs O(vertices) per deforming object here, as it does to produce. An object that changes
// between rigid and deforming is refused (std::invalid_argument).
void sync_bodies(World& world, const std::vector<Object>& objects, std::vector<BodyId>& bodies);

}  // namespace peelcd
