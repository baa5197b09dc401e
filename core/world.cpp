#include "peelcd/core/world.h"
#include "peelcd/core/clock.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/cull.h"
#include "peelcd/core/reference.h"
#include "peelcd/core/cpu_stage.h"
#include "peelcd/core/id_map.h"
#include "peelcd/core/narrow_phase.h"
#include "peelcd/core/self.h"
#include "peelcd/core/worker_pool.h"
#include "exclusive_use.h"

#include <algorithm>
#include <map>
#include <atomic>
#include <chrono>
#include <stdexcept>

namespace peelcd {
namespace {

constexpr double kCandidateUs = kWorldCandidateUs;
constexpr std::uint32_t kSmallPair = 0xffffffffu;  // a task's start: scan two small world meshes
constexpr std::uint32_t kSelfPair = 0xfffffffeu;   // a task's start: a body's self traversal

// A rigid body with fewer triangles than this is moved into world space every frame (its
// vertices transformed, a world-space copy of its tree refitted): O(its size), a few
// microseconds, and its boxes are then exact world boxes, where boxes carried through a rotation
// grow (a small ball's tree seen from a neighbour's frame overlaps far more of it). Larger rigid
// bodies are never touched beyond what the traversal reaches.
// 8,192: against 4,096, test1's 4,512-triangle balls moved into world space, its frame 1.08 ->
// 0.65 ms (boxes carried through a pose cost a transform per node pair).
constexpr std::size_t kWorldFrameTriangles = 8192;

struct Body {
  bool alive = false;
  bool is_rigid = false;
  std::string name;
  std::shared_ptr<const Mesh> shape;  // rigid
  Mesh mesh;                          // deforming: world space
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
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
  // Deforming: its tree is refitted whole at the next collide() (set_vertices, many moved
  // vertices), every such body's triangles split over the frame's lanes.
  bool refit_pending = false;
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
  std::vector<Contact> self_contacts;
  void topology_changed() {
    rep_valid = false;
    self_cached = false;
  }
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
  // Small (under kWorldFrameTriangles) and in world space this frame: a pair of two such bodies,
  // one of them a rigid body that moved, is tested as the frame API tests it (one culling round
  // over both meshes, a sweep of the kept triangles' boxes): that scan costs less than refitting
  // the moved body's world-space tree. Otherwise the trees are current (deforming bodies'
  // refitted, a still rigid body's world tree kept): their traversal costs less than the scan
  // (the default scene: 0.24 vs 0.35 ms a frame).
  bool small() const { return local().triangles.size() < kWorldFrameTriangles; }
  const Mesh* world_mesh() const { return !is_rigid ? &mesh : world_frame ? &world_copy : nullptr; }
  // The tree the traversals use and the pose it is posed by: a small rigid body's world copy
  // (identity), else its own.
  const Bvh& frame_tree() const { return world_frame ? world_tree : tree; }
  Eigen::Affine3d frame_pose() const { return world_frame ? Eigen::Affine3d::Identity() : pose; }
  // Small rigid bodies: into world space for this frame (the tree only when needed:
  // ensure_world_tree()).
  // Returns the vertices transformed.
  std::size_t enter_frame() {
    world_frame = is_rigid && shape->triangles.size() < kWorldFrameTriangles;
    moved = false;
    if (!world_frame) {
      copy_valid = world_tree_fresh = false;
      return 0;
    }
    if (copy_valid && copied_pose.matrix() == pose.matrix()) return 0;  // unchanged since the last copy
    world_tree_fresh = false;
    moved = true;
    if (world_copy.triangles.size() != shape->triangles.size()) world_copy.triangles = shape->triangles;
    world_copy.vertices.resize(shape->vertices.size());
    for (std::size_t v = 0; v < world_copy.vertices.size(); ++v) world_copy.vertices[v] = pose * shape->vertices[v];
    world_copy_box = world_copy.triangles.empty() ? Aabb{} : bounds(world_copy);
    copied_pose = pose;
    copy_valid = true;
    return world_copy.vertices.size();
  }
  void ensure_world_tree() {
    if (!world_frame || world_tree_fresh) return;
    if (world_tree.triangles() != shape->triangles.size() || world_tree.empty() != tree.empty())
      world_tree.build(world_copy.vertices, world_copy.triangles);
    else
      world_tree.refit(world_copy.vertices, world_copy.triangles);
    world_tree_fresh = true;
  }
  Aabb world_box() const {
    if (world_frame) return world_copy_box;
    const Aabb b = tree.box();
    if (!is_rigid || b.empty()) return b;
    // The root box moved by the pose, grown as the traversal grows its boxes.
    return BvhRelation::moved(b, pose.linear(), pose.linear().cwiseAbs(), pose.translation(),
                              pose.translation().cwiseAbs().maxCoeff());
  }
};

std::string label_of(const std::string& name, BodyId id) {
  return "body " + std::to_string(id) + (name.empty() ? "" : " '" + name + "'");
}

void check_mesh(const Mesh& m, const std::string& label) {
  const auto fail = [&](const std::string& problem) { throw std::invalid_argument("peelcd::World: " + label + problem); };
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (!m.vertices[v].allFinite()) fail(": vertex " + std::to_string(v) + " " + coordinate_problem(m.vertices[v], false));
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (const std::uint32_t v : m.triangles[f])
      if (v >= m.vertices.size())
        fail(": triangle " + std::to_string(f) + " uses vertex " + std::to_string(v) + " but the mesh has " +
             std::to_string(m.vertices.size()) + " vertices");
  if (std::max(m.triangles.size(), m.vertices.size()) >= 0x7fffffffu)
    fail(" has 2^31 - 1 or more triangles or vertices; IDs hold 31 bits");
}

void check_pose(const Eigen::Affine3d& pose, const std::string& label) {
  if (const std::string problem = pose_problem(pose); !problem.empty())
    throw std::invalid_argument("peelcd::World: " + label + ": its pose " + problem);
}

// One piece of a pair's traversal: a node pair, the candidates found under it, then (exact
// path) the contacts among them, in candidate order.
struct Task {
  std::size_t pair = 0;
  BvhNodePair start;
  std::vector<std::uint64_t> candidates;
  std::vector<Contact> contacts;
  std::size_t visited = 0, transformed = 0;
  std::size_t tested = 0;  // a self task's couples given to the exact test
};

}  // namespace

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
  std::vector<std::size_t> order;
  std::vector<Task> tasks;
  std::vector<BvhNodePair> split;
  std::vector<std::vector<BvhStackEntry>> stacks;  // per lane
  std::vector<std::vector<BvhNodePair>> self_stacks;  // per lane
  struct LaneScratch {
    ContactCull cull;
    BoxScratch boxes;
    std::vector<std::uint64_t> sorted;
  };
  std::vector<std::unique_ptr<LaneScratch>> lane_scratch;  // per lane: the small pairs' scan
  std::vector<std::uint64_t> candidates;
  std::vector<std::size_t> first_task;  // pair p's tasks: [first_task[p], first_task[p + 1])
  std::vector<char> to_image;           // pair p goes to the image stage
  std::vector<Aabb> body_boxes;         // per BodyId, this frame's world box
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
  BodyId add(Body b) {
    b.alive = true;
    b.tree.build(b.local().vertices, b.local().triangles);
    ++stats.builds;
    ++alive;
    bodies.push_back(std::move(b));
    return BodyId(bodies.size() - 1);
  }

  unsigned lanes_for(const DetectOptions& opt) {
    if (opt.threads == 1) return 1;
    if (!pool || (opt.threads != 0 && pool->lanes() != opt.threads)) pool = std::make_unique<WorkerPool>(opt.threads);
    return pool->lanes();
  }
  // body(i, lane) for i in [0, n), spread over the pool's lanes when there are several.
  template <class Fn>
  void parallel(std::size_t n, unsigned lanes, Fn&& fn) {
    if (stacks.size() < lanes) stacks.resize(lanes);
    if (self_stacks.size() < lanes) self_stacks.resize(lanes);
    while (lane_scratch.size() < lanes) lane_scratch.push_back(std::make_unique<LaneScratch>());
    if (lanes <= 1 || n <= 1) {
      for (std::size_t i = 0; i < n; ++i) fn(i, 0u);
      return;
    }
    std::atomic<std::size_t> next{0};
    auto job = [&](unsigned lane) {
      for (std::size_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) fn(i, lane);
    };
    pool->run(job);
  }

  // The deferred whole-tree refits (World::set_vertices, many moved vertices): every pending
  // body's triangle boxes in chunks over the lanes (a large body split in as many chunks as
  // lanes), then each body's nodes.
  struct RefitChunk {
    std::size_t begin, end;
    Aabb exact;
  };
  struct RefitBody {
    Body* body;
    std::size_t first, last;  // its chunks in refit_chunks
  };
  std::vector<RefitChunk> refit_chunks;
  std::vector<RefitBody> refit_bodies;
  std::vector<std::size_t> refit_owner;  // chunk -> its entry in refit_bodies
  void refit_pending(unsigned lanes) {
    refit_chunks.clear();
    refit_bodies.clear();
    refit_owner.clear();
    for (Body& b : bodies) {
      if (!b.alive || !b.refit_pending) continue;
      const std::size_t n = b.mesh.triangles.size();
      const std::size_t parts = lanes > 1 && n >= 32768 ? lanes : 1;
      refit_bodies.push_back({&b, refit_chunks.size(), refit_chunks.size() + parts});
      for (std::size_t k = 0; k < parts; ++k) {
        refit_chunks.push_back({n * k / parts, n * (k + 1) / parts, Aabb{}});
        refit_owner.push_back(refit_bodies.size() - 1);
      }
    }
    if (refit_bodies.empty()) return;
    parallel(refit_chunks.size(), lanes, [&](std::size_t k, unsigned) {
      RefitChunk& c = refit_chunks[k];
      Body& b = *refit_bodies[refit_owner[k]].body;
      c.exact = b.tree.refit_triangles(b.mesh.vertices, b.mesh.triangles, c.begin, c.end);
    });
    parallel(refit_bodies.size(), lanes, [&](std::size_t k, unsigned) {
      const RefitBody& r = refit_bodies[k];
      Aabb exact;
      for (std::size_t c = r.first; c < r.last; ++c)
        exact.lo = exact.lo.cwiseMin(refit_chunks[c].exact.lo), exact.hi = exact.hi.cwiseMax(refit_chunks[c].exact.hi);
      r.body->tree.refit_nodes(exact);
      r.body->refit_pending = false;
    });
    stats.full_refits += refit_bodies.size();
  }
  // One body's pending refit now (World::tree() asked for it between frames).
  void refit_now(Body& b) {
    if (!b.refit_pending) return;
    b.tree.refit(b.mesh.vertices, b.mesh.triangles);
    b.refit_pending = false;
    ++stats.full_refits;
  }

  void collide(const DetectOptions& opt, FrameResult& out);
  // A self pair's contacts: its tasks' (in the body's frame), cached for a rigid body, moved to
  // world space.
  void self_pair(Body& a, std::size_t first, std::size_t last, PairResult& r) {
    if (!(a.is_rigid && a.self_cached)) {
      a.self_contacts.clear();
      std::size_t n = 0;
      for (std::size_t k = first; k < last; ++k) {
        a.self_contacts.insert(a.self_contacts.end(), tasks[k].contacts.begin(), tasks[k].contacts.end());
        n += tasks[k].tested;
      }
      std::sort(a.self_contacts.begin(), a.self_contacts.end(), [](const Contact& x, const Contact& y) {
        return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
      });
      a.self_cached = a.is_rigid;
      r.candidates = n;
    } else {
      r.candidates = 0;  // nothing tested this frame
    }
    r.colliding = a.self_contacts;
    if (a.is_rigid)
      for (Contact& c : r.colliding) {
        c.p = a.pose * c.p;
        c.q = a.pose * c.q;
      }
  }
  // The image-routed pairs (or pair `only` alone) through the Detector in one frame.
  static constexpr std::size_t kAllPairs = std::size_t(-1);
  void image_pairs(const DetectOptions& opt, FrameResult& out, std::size_t only = kAllPairs);
  std::optional<bool> batch_pairs;  // World::batch_image_pairs()
  bool batched_image() const {
    if (batch_pairs) return *batch_pairs;
    const std::string& r = stage->renderer();
    for (const char* soft : {"llvmpipe", "softpipe", "swrast"})
      if (r.find(soft) != std::string::npos) return false;
    return stage->backend() != "cpu";
  }
  // The image-routed pairs' objects (two a pair), their triangles' indices in the bodies, the
  // pair each came from, and the object pairs the Detector is asked for.
  std::vector<Object> image_objects;
  std::vector<std::vector<std::uint32_t>> image_kept;
  std::vector<std::size_t> image_of;
  std::vector<std::pair<std::size_t, std::size_t>> image_only;
};

World::World(std::shared_ptr<ImageStage> stage) : impl_(std::make_unique<Impl>()) {
  impl_->stage = stage ? std::move(stage) : std::make_shared<CpuImageStage>();
}
World::~World() = default;

BodyId World::add_rigid(std::shared_ptr<const Mesh> shape, const Eigen::Affine3d& pose, std::string name) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  const std::string label = label_of(name, BodyId(impl_->bodies.size()));
  if (!shape) throw std::invalid_argument("peelcd::World: " + label + ": no shape");
  check_mesh(*shape, label);
  check_pose(pose, label);
  Body b;
  b.is_rigid = true;
  b.name = std::move(name);
  b.shape = std::move(shape);
  b.pose = pose;
  return impl_->add(std::move(b));
}

BodyId World::add_deforming(Mesh mesh, std::string name) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  check_mesh(mesh, label_of(name, BodyId(impl_->bodies.size())));
  Body b;
  b.name = std::move(name);
  b.mesh = std::move(mesh);
  return impl_->add(std::move(b));
}

void World::remove(BodyId id) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "remove");
  b = Body{};
  --impl_->alive;
}

void World::set_pose(BodyId id, const Eigen::Affine3d& pose) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_pose");
  if (!b.is_rigid) throw std::invalid_argument("peelcd::World::set_pose(): " + label_of(b.name, id) + " is deforming");
  check_pose(pose, label_of(b.name, id));
  b.pose = pose;
}

namespace {
// Throws unless `vertices` fit deforming body `b` (same count, finite).
void check_vertices(const Body& b, const std::string& label, const std::vector<Vec3>& vertices) {
  if (b.is_rigid) throw std::invalid_argument("peelcd::World::set_vertices(): " + label + " is rigid (use set_pose)");
  if (vertices.size() != b.mesh.vertices.size())
    throw std::invalid_argument("peelcd::World::set_vertices(): " + label + " has " + std::to_string(b.mesh.vertices.size()) +
                                " vertices, given " + std::to_string(vertices.size()) + " (a new topology: set_mesh)");
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (!vertices[v].allFinite())
      throw std::invalid_argument("peelcd::World::set_vertices(): " + label + ": vertex " + std::to_string(v) + " " +
                                  coordinate_problem(vertices[v], false));
}
}  // namespace

void World::set_vertices(BodyId id, const std::vector<Vec3>& vertices) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_vertices");
  check_vertices(b, label_of(b.name, id), vertices);
  std::copy(vertices.begin(), vertices.end(), b.mesh.vertices.begin());  // into the body's storage
  b.refit_pending = true;
}

void World::set_vertices(BodyId id, std::vector<Vec3>&& vertices) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_vertices");
  check_vertices(b, label_of(b.name, id), vertices);
  b.mesh.vertices = std::move(vertices);
  b.refit_pending = true;
}

void World::move_vertices(BodyId id, const std::vector<std::uint32_t>& indices, const std::vector<Vec3>& positions) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "move_vertices");
  const std::string label = label_of(b.name, id);
  if (b.is_rigid) throw std::invalid_argument("peelcd::World::move_vertices(): " + label + " is rigid (use set_pose)");
  if (indices.size() != positions.size())
    throw std::invalid_argument("peelcd::World::move_vertices(): " + label + ": " + std::to_string(indices.size()) +
                                " indices but " + std::to_string(positions.size()) + " positions");
  const std::size_t nv = b.mesh.vertices.size();
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (indices[k] >= nv)
      throw std::invalid_argument("peelcd::World::move_vertices(): " + label + ": vertex " + std::to_string(indices[k]) +
                                  " is out of range (the mesh has " + std::to_string(nv) + " vertices)");
    if (!positions[k].allFinite())
      throw std::invalid_argument("peelcd::World::move_vertices(): " + label + ": vertex " + std::to_string(indices[k]) +
                                  " " + coordinate_problem(positions[k], false));
  }
  for (std::size_t k = 0; k < indices.size(); ++k) b.mesh.vertices[indices[k]] = positions[k];
  // Many moved: one sweep over the tree is cheaper than the paths (a sweep already pending
  // covers these too).
  if (b.refit_pending || indices.size() * 8 > nv) {
    b.refit_pending = true;
    return;
  }
  if (b.vertex_first.empty()) {  // the vertex -> triangles table, once per topology
    b.vertex_first.assign(nv + 1, 0);
    for (const Tri& f : b.mesh.triangles)
      for (const std::uint32_t v : f) ++b.vertex_first[v + 1];
    for (std::size_t v = 0; v < nv; ++v) b.vertex_first[v + 1] += b.vertex_first[v];
    b.vertex_tris.resize(b.vertex_first[nv]);
    std::vector<std::uint32_t> fill(b.vertex_first.begin(), b.vertex_first.end() - 1);
    for (std::uint32_t t = 0; t < b.mesh.triangles.size(); ++t)
      for (const std::uint32_t v : b.mesh.triangles[t]) b.vertex_tris[fill[v]++] = t;
  }
  std::vector<std::uint32_t> changed;
  for (const std::uint32_t v : indices)
    changed.insert(changed.end(), b.vertex_tris.begin() + b.vertex_first[v], b.vertex_tris.begin() + b.vertex_first[v + 1]);
  b.tree.refit(b.mesh.vertices, b.mesh.triangles, changed);
  ++impl_->stats.partial_refits;
}

void World::set_mesh(BodyId id, Mesh mesh) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_mesh");
  check_mesh(mesh, label_of(b.name, id));
  if (b.is_rigid)
    b.shape = std::make_shared<const Mesh>(std::move(mesh));
  else
    b.mesh = std::move(mesh);
  b.vertex_first.clear();
  b.vertex_tris.clear();
  b.topology_changed();
  b.tree.build(b.local().vertices, b.local().triangles);
  b.refit_pending = false;
  b.world_tree = Bvh{};
  b.world_copy = Mesh{};
  b.copy_valid = false;
  ++impl_->stats.builds;
}

void World::set_shape(BodyId id, std::shared_ptr<const Mesh> shape) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_shape");
  const std::string label = label_of(b.name, id);
  if (!b.is_rigid) throw std::invalid_argument("peelcd::World::set_shape(): " + label + " is deforming (use set_mesh)");
  if (!shape) throw std::invalid_argument("peelcd::World::set_shape(): " + label + ": no shape");
  check_mesh(*shape, label);
  b.shape = std::move(shape);
  b.topology_changed();
  b.tree.build(b.shape->vertices, b.shape->triangles);
  b.world_tree = Bvh{};
  b.world_copy = Mesh{};
  b.copy_valid = false;
  ++impl_->stats.builds;
}

void World::set_self(BodyId id, bool self) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  impl_->body(id, "set_self").self = self;
}
bool World::self(BodyId id) const { return impl_->body(id).self; }

bool World::contains(BodyId id) const { return id < impl_->bodies.size() && impl_->bodies[id].alive; }
std::size_t World::size() const { return impl_->alive; }
const std::string& World::name(BodyId id) const { return impl_->body(id).name; }
bool World::rigid(BodyId id) const { return impl_->body(id).is_rigid; }
const Mesh& World::mesh(BodyId id) const { return impl_->body(id).local(); }
const Bvh& World::tree(BodyId id) const {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "tree");
  impl_->refit_now(b);
  return b.tree;
}
const WorldStats& World::stats() const { return impl_->stats; }
ImageStage& World::stage() { return *impl_->stage; }
void World::batch_image_pairs(std::optional<bool> together) { impl_->batch_pairs = together; }

Mesh World::world_mesh(BodyId id) const {
  const Body& b = impl_->body(id);
  Mesh m = b.local();
  if (b.is_rigid)
    for (std::uint32_t v = 0; v < m.vertices.size(); ++v) m.vertices[v] = b.pose * b.shape->vertices[v];
  return m;
}

const FrameResult& World::collide(const DetectOptions& options) {
  impl_->collide(options, impl_->result);
  return impl_->result;
}

void World::collide(const DetectOptions& options, FrameResult& out) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  impl_->collide(options, out);
}

void World::Impl::collide(const DetectOptions& opt, FrameResult& out) {
  validate_options(opt, stage->max_resolution());
  const auto t_total = Clock::now();
  out.reset_counters();
  stats.node_pairs = stats.candidates = stats.vertices_transformed = 0;
  refit_pending(lanes_for(opt));

  // The broad phase: each body's box (its tree's root, moved by its pose).
  auto t0 = Clock::now();
  boxes.clear();
  ids.clear();
  for (BodyId id = 0; id < bodies.size(); ++id) {
    if (!bodies[id].alive) continue;
    stats.vertices_transformed += bodies[id].enter_frame();
    ids.push_back(id);
    boxes.push_back(bodies[id].world_box());
    const Aabb& w = boxes.back();
    if (opt.stage != Stage::exact && !w.empty() &&
        std::max(w.lo.cwiseAbs().maxCoeff(), w.hi.cwiseAbs().maxCoeff()) > kFloatMax)
      throw std::invalid_argument("peelcd::World: " + label_of(bodies[id].name, id) +
                                  " reaches outside the float range (|x| <= 3.4e38) the image stage works in");
  }
  overlapping_pairs(boxes, pairs, order);  // indices into ids, ascending ids: a < b
  // Self pairs (i, i): the bodies asking for self-collision (set_self, DetectOptions::self).
  bool any_self = false;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    Body& b = bodies[ids[i]];
    if (!(opt.self || b.self) || b.local().triangles.size() < 2) continue;
    b.representatives(opt.self_adjacency);
    pairs.emplace_back(i, i);
    any_self = true;
  }
  if (any_self) std::sort(pairs.begin(), pairs.end());

  // The traversals: per pair, one task, or (several lanes) the node pairs of its first levels.
  const unsigned lanes = lanes_for(opt);
  std::size_t used = 0;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    Body& a = bodies[ids[pairs[p].first]];
    Body& b = bodies[ids[pairs[p].second]];
    if (&a == &b) {  // self: one traversal of the body's own tree (none for a rigid body's cache)
      split.clear();
      if (!(a.is_rigid && a.self_cached)) split.assign(1, BvhNodePair{kSelfPair, kSelfPair});
    } else if (a.small() && b.small() && a.world_mesh() && b.world_mesh() && (a.moved || b.moved)) {
      split.assign(1, BvhNodePair{kSmallPair, kSmallPair});
    } else {
      a.ensure_world_tree();
      b.ensure_world_tree();
      if (lanes > 1)
        bvh_split(a.frame_tree(), b.frame_tree(), BvhRelation::between(a.frame_pose(), b.frame_pose()),
                  8 * std::size_t(lanes), split);
      else
        split.assign(1, BvhNodePair{0u, 0u});
    }
    for (const BvhNodePair& start : split) {
      if (used == tasks.size()) tasks.emplace_back();
      Task& t = tasks[used++];
      t.pair = p;
      t.start = start;
    }
  }
  parallel(used, lanes, [&](std::size_t k, unsigned lane) {
    Task& t = tasks[k];
    const Body& a = bodies[ids[pairs[t.pair].first]];
    const Body& b = bodies[ids[pairs[t.pair].second]];
    t.candidates.clear();
    t.contacts.clear();
    t.transformed = 0;
    t.tested = 0;
    if (t.start.first == kSelfPair) {  // in the body's own frame, adjacent couples dropped,
      const Mesh& m = a.local();      // each couple tested as the traversal reaches it
      t.visited = bvh_self_traverse(a.tree, self_stacks[lane], [&](std::uint32_t x, std::uint32_t y) {
        if (triangles_adjacent(m, a.rep, x, y)) return;
        ++t.tested;
        Contact contact;
        contact.tri_a = std::min(x, y);
        contact.tri_b = std::max(x, y);
        if (test_self_couple(corners(m, contact.tri_a), corners(m, contact.tri_b), contact)) t.contacts.push_back(contact);
      });
      return;
    }
    if (t.start.first == kSmallPair) {  // as the frame API's exact path: one culling round, a sweep
      const Mesh& ma = *a.world_mesh();
      const Mesh& mb = *b.world_mesh();
      LaneScratch& s = *lane_scratch[lane];
      cull_to_contact_region(ma, mb, intersection(boxes[pairs[t.pair].first], boxes[pairs[t.pair].second]), s.cull, 1);
      if (!s.cull.box.empty()) box_overlap_pairs(ma, s.cull.kept_a, mb, s.cull.kept_b, t.candidates, &s.boxes);
      t.visited = 0;
      return;
    }
    const BvhRelation rel = BvhRelation::between(a.frame_pose(), b.frame_pose());
    t.visited = bvh_traverse(a.frame_tree(), b.frame_tree(), rel, t.start, stacks[lane],
                             [&](std::uint32_t ta, std::uint32_t tb) { t.candidates.push_back(pack_pair(ta, tb)); });
  });
  out.timings.aabb = ms_since(t0);

  // Per pair: the route, then the exact path's narrow phase (over the same tasks) or the image
  // stage.
  out.pairs.resize(pairs.size());
  first_task.assign(pairs.size() + 1, used);
  for (std::size_t k = used; k-- > 0;) first_task[tasks[k].pair] = k;
  for (std::size_t p = pairs.size(); p-- > 0;)
    if (first_task[p] > first_task[p + 1]) first_task[p] = first_task[p + 1];
  const StageCost image_cost = stage->router_image_cost();
  to_image.assign(pairs.size(), 0);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    PairResult& r = out.pairs[p];
    std::vector<Contact> colliding = std::move(r.colliding);  // its storage reused frame to frame
    colliding.clear();
    r = PairResult{};
    r.colliding = std::move(colliding);
    r.object_a = ids[pairs[p].first];
    r.object_b = ids[pairs[p].second];
    r.roi = r.region = intersection(boxes[pairs[p].first], boxes[pairs[p].second]);
    std::size_t n = 0;
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) {
      n += tasks[k].candidates.size();
      stats.node_pairs += tasks[k].visited;
    }
    stats.candidates += n;
    r.candidates = n;
    if (r.object_a == r.object_b) {  // self: the exact path always (docs/design.md)
      r.exact_stage = true;
      continue;
    }
    if (n == 0) continue;  // no couple of boxes overlaps: no contact, nothing to test
    if (opt.stage == Stage::exact) {
      r.exact_stage = true;
    } else if (opt.stage == Stage::image) {
      to_image[p] = 1;
    } else {
      const int tile = opt.resolution > 0 ? opt.resolution : opt.budget;
      r.predicted_exact_ms = kCandidateUs * 1e-3 * double(n);
      // The image stage draws at most the candidates' triangles: at most 2n, counted as n.
      r.predicted_image_ms = double(opt.views) * image_cost.predict_ms(double(n), double(tile) * double(tile));
      r.exact_stage = r.predicted_exact_ms <= r.predicted_image_ms;
      to_image[p] = !r.exact_stage;
    }
  }
  t0 = Clock::now();
  parallel(used, lanes, [&](std::size_t k, unsigned lane) {
    Task& t = tasks[k];
    if (t.candidates.empty() || to_image[t.pair]) return;
    const Body& a = bodies[ids[pairs[t.pair].first]];
    const Body& b = bodies[ids[pairs[t.pair].second]];
    if (t.start.first == kSelfPair) return;  // tested during the traversal
    if (t.start.first == kSmallPair) {  // the sweep's pairs: distinct, boxes overlapping, world meshes at hand
      sort_unique_pairs(t.candidates, lane_scratch[lane]->sorted);
      narrow_phase(*a.world_mesh(), *b.world_mesh(), t.candidates, t.contacts, /*boxes_overlap=*/true,
                   opt.max_contacts);
      return;
    }
    const Mesh& ma = a.local();
    const Mesh& mb = b.local();
    // In traversal order (deterministic; the pair's contacts are sorted below): sorting the
    // candidates first cost 2-12% of a frame and bought nothing.
    for (const std::uint64_t c : t.candidates) {
      const std::uint32_t ta = pair_a(c), tb = pair_b(c);
      const Tri& fa = ma.triangles[ta];
      const Tri& fb = mb.triangles[tb];
      const TriangleCorners ca = {a.world(fa[0]), a.world(fa[1]), a.world(fa[2])};
      const TriangleCorners cb = {b.world(fb[0]), b.world(fb[1]), b.world(fb[2])};
      t.transformed += (a.is_rigid && !a.world_frame ? 3 : 0) + (b.is_rigid && !b.world_frame ? 3 : 0);
      // The world boxes first (exact comparisons of the same doubles the test reads).
      const Vec3 lo_a = ca[0].cwiseMin(ca[1]).cwiseMin(ca[2]), hi_a = ca[0].cwiseMax(ca[1]).cwiseMax(ca[2]);
      const Vec3 lo_b = cb[0].cwiseMin(cb[1]).cwiseMin(cb[2]), hi_b = cb[0].cwiseMax(cb[1]).cwiseMax(cb[2]);
      if ((hi_a.array() < lo_b.array()).any() || (hi_b.array() < lo_a.array()).any()) continue;
      Contact contact;
      contact.tri_a = ta;
      contact.tri_b = tb;
      if (test_triangle_pair(ca, cb, contact)) {
        t.contacts.push_back(contact);
        if (opt.max_contacts && t.contacts.size() >= opt.max_contacts) return;  // enough for this task
      }
    }
  });
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    PairResult& r = out.pairs[p];
    if (r.object_a == r.object_b) {
      self_pair(bodies[r.object_a], first_task[p], first_task[p + 1], r);
      ++out.rois_exact;
      continue;
    }
    if (r.candidates == 0 || to_image[p]) continue;
    ++out.rois_exact;
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) {
      r.colliding.insert(r.colliding.end(), tasks[k].contacts.begin(), tasks[k].contacts.end());
      stats.vertices_transformed += tasks[k].transformed;
    }
    std::sort(r.colliding.begin(), r.colliding.end(), [](const Contact& x, const Contact& y) {
      return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
    });
  }
  out.timings.cpu = ms_since(t0);

  if (batched_image()) {
    image_pairs(opt, out);
  } else {
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      if (!to_image[p]) continue;
      image_pairs(opt, out, p);
    }
  }
  // Relations (containment where no contact) and, asked for, volumes: world meshes made only
  // for the pairs that need them.
  t0 = Clock::now();
  body_boxes.assign(bodies.size(), Aabb{});
  for (std::size_t i = 0; i < ids.size(); ++i) body_boxes[ids[i]] = boxes[i];
  world_meshes.clear();
  relate_pairs(
      out.pairs,
      [&](std::size_t id) -> const Mesh& {
        const Body& b = bodies[id];
        if (const Mesh* m = b.world_mesh()) return *m;
        auto it = world_meshes.find(id);
        if (it == world_meshes.end()) {
          Mesh m = *b.shape;
          for (Vec3& v : m.vertices) v = b.pose * v;
          it = world_meshes.emplace(id, std::move(m)).first;
        }
        return it->second;
      },
      body_boxes, opt);
  out.timings.cpu += ms_since(t0);
  out.renderer = stage->renderer();
  out.timings.total = ms_since(t_total);
}

// The image stage on every pair routed there, in one frame of the Detector (one batch of views
// for all of them): per pair, the candidates' triangles of each body, in world space, as two
// objects (triangle k of each is the k-th of its ascending list), the Detector asked for those
// pairs alone (Detector::only_pairs()); the contacts mapped back to the bodies' triangles.
void World::Impl::image_pairs(const DetectOptions& opt, FrameResult& out, std::size_t only) {
  image_objects.clear();
  image_kept.clear();
  image_of.clear();
  image_only.clear();
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!to_image[p] || (only != kAllPairs && p != only)) continue;
    const Body* body[2] = {&bodies[ids[pairs[p].first]], &bodies[ids[pairs[p].second]]};
    std::vector<std::uint32_t> kept[2];
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k)
      for (const std::uint64_t c : tasks[k].candidates) {
        kept[0].push_back(pair_a(c));
        kept[1].push_back(pair_b(c));
      }
    const std::size_t first = image_objects.size();
    for (int s = 0; s < 2; ++s) {
      std::sort(kept[s].begin(), kept[s].end());
      kept[s].erase(std::unique(kept[s].begin(), kept[s].end()), kept[s].end());
      Object o;
      const Mesh& local = body[s]->local();
      for (const std::uint32_t t : kept[s]) {
        const std::uint32_t base = std::uint32_t(o.mesh.vertices.size());
        for (const std::uint32_t v : local.triangles[t]) o.mesh.vertices.push_back(body[s]->world(v));
        o.mesh.triangles.push_back(Tri{base, base + 1, base + 2});
      }
      o.name = body[s]->name;
      image_objects.push_back(std::move(o));
      image_kept.push_back(std::move(kept[s]));
    }
    image_only.emplace_back(first, first + 1);
    image_of.push_back(p);
  }
  if (image_of.empty()) return;
  if (!detector) detector = std::make_unique<Detector>(stage);
  DetectOptions image = opt;
  image.stage = Stage::image;
  FrameResult inner;
  struct Only {  // the Detector back to every pair, also on an exception
    Detector& d;
    ~Only() { d.only_pairs(nullptr); }
  } reset_pairs{*detector};
  detector->only_pairs(&image_only);
  detector->detect(image_objects, image, inner);
  for (const PairResult& ir : inner.pairs) {
    const std::size_t i = ir.object_a / 2;
    const std::vector<std::uint32_t>& ka = image_kept[2 * i];
    const std::vector<std::uint32_t>& kb = image_kept[2 * i + 1];
    PairResult& r = out.pairs[image_of[i]];
    const double pe = r.predicted_exact_ms, pi = r.predicted_image_ms;
    const std::size_t oa = r.object_a, ob = r.object_b;
    const Aabb roi = r.roi;
    r = ir;
    r.object_a = oa;
    r.object_b = ob;
    r.roi = roi;
    r.predicted_exact_ms = pe;
    r.predicted_image_ms = pi;
    r.triangles_in_roi_a = ka.size();
    r.triangles_in_roi_b = kb.size();
    r.pcs.clear();  // IDs of the peeled copies, not of the bodies: the count (pcs_count) stays
    for (Contact& c : r.colliding) {
      c.tri_a = ka[c.tri_a];
      c.tri_b = kb[c.tri_b];
    }
    std::sort(r.colliding.begin(), r.colliding.end(), [](const Contact& x, const Contact& y) {
      return x.tri_a < y.tri_a || (x.tri_a == y.tri_a && x.tri_b < y.tri_b);
    });
  }
  out.add_image_work(inner);
}

void sync_bodies(World& world, const std::vector<Object>& objects, std::vector<BodyId>& bodies) {
  if (bodies.empty()) {
    for (const Object& o : objects) {
      bodies.push_back(o.rigid ? world.add_rigid(o.rigid->shape, o.rigid->pose, o.name) : world.add_deforming(o.mesh, o.name));
      world.set_self(bodies.back(), o.self);
    }
    return;
  }
  if (bodies.size() != objects.size())
    throw std::invalid_argument("peelcd::sync_bodies(): " + std::to_string(objects.size()) + " objects for " +
                                std::to_string(bodies.size()) + " bodies");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const Object& o = objects[i];
    const BodyId id = bodies[i];
    if (bool(o.rigid) != world.rigid(id))
      throw std::invalid_argument("peelcd::sync_bodies(): object " + std::to_string(i) + " '" + o.name +
                                  "' changed between rigid and deforming");
    world.set_self(id, o.self);
    if (o.rigid) {
      if (&world.mesh(id) != o.rigid->shape.get()) world.set_shape(id, o.rigid->shape);
      world.set_pose(id, o.rigid->pose);
    } else if (o.mesh.triangles == world.mesh(id).triangles) {
      world.set_vertices(id, o.mesh.vertices);
    } else {
      world.set_mesh(id, o.mesh);
    }
  }
}

}  // namespace peelcd
