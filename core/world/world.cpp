#include "world_impl.h"
#include "peelcd/core/exclusive_use.h"
#include "peelcd/core/image/cpu_stage.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {
namespace {

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

// Throws unless `pose` is finite and invertible; label() names the body, called only into an
// error (set_pose() runs every frame and allocates nothing).
template <class Label>
void check_pose(const Eigen::Affine3d& pose, const Label& label) {
  if (const std::string problem = pose_problem(pose); !problem.empty())
    throw std::invalid_argument("peelcd::World: " + label() + ": its pose " + problem);
}

}  // namespace

World::World(std::shared_ptr<ImageStage> stage) : impl_(std::make_unique<Impl>()) {
  impl_->stage = stage ? std::move(stage) : std::make_shared<CpuImageStage>();
}
World::~World() = default;

BodyId World::add_rigid(std::shared_ptr<const Mesh> shape, const Eigen::Affine3d& pose, std::string name) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  const std::string label = label_of(name, BodyId(impl_->bodies.size()));
  if (!shape) throw std::invalid_argument("peelcd::World: " + label + ": no shape");
  check_mesh(*shape, label);
  check_pose(pose, [&] { return label; });
  Body b;
  b.is_rigid = true;
  b.name = std::move(name);
  b.shape = std::move(shape);
  b.set_pose(pose);
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
  if (!b.name.empty()) impl_->names.erase(b.name);
  b = Body{};
  --impl_->alive;
}

void World::set_pose(BodyId id, const Eigen::Affine3d& pose) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_pose");
  if (!b.is_rigid) throw std::invalid_argument("peelcd::World::set_pose(): " + label_of(b.name, id) + " is deforming");
  if (pose.matrix() == b.pose.matrix()) return;  // the pose it has (checked when it was set)
  check_pose(pose, [&] { return label_of(b.name, id); });
  b.set_pose(pose);
}

namespace {
// A body this large has its new vertices checked, rounded and copied in parts over the last
// frame's lanes (the waving 1.3M-triangle spheres' 650k vertices a body).
constexpr std::size_t kSplitVertices = 65536;

// Throws unless `vertices` fit deforming body `b` (the same count). Its label is built only
// into an error (a steady frame allocates nothing).
void check_count(const Body& b, BodyId id, const std::vector<Vec3>& vertices) {
  if (b.is_rigid)
    throw std::invalid_argument("peelcd::World::set_vertices(): " + label_of(b.name, id) + " is rigid (use set_pose)");
  if (vertices.size() != b.mesh.vertices.size())
    throw std::invalid_argument("peelcd::World::set_vertices(): " + label_of(b.name, id) + " has " +
                                std::to_string(b.mesh.vertices.size()) + " vertices, given " +
                                std::to_string(vertices.size()) + " (a new topology: set_mesh)");
}

// Checks `vertices` finite and rounds them into b's tree in one pass (Bvh::load_vertices), in
// `parts` parts over the World's lanes (w: World::Impl, in_parts(); its part_bad and part_boxes
// hold each part's first bad vertex and box), copying them to `copy` (when not null); throws at
// the first vertex that is not finite, the body's vertices and tree as they were (its floats to
// be rounded again by the refit).
template <class Lanes>
void load_vertices(Lanes& w, Body& b, BodyId id, const std::vector<Vec3>& vertices, Vec3* copy, std::size_t parts) {
  // Rounded into the tree only where the last refit came: a body whose refit is still pending
  // (put off by the resident image route, which draws it from its vertices) is likely to put
  // it off again, and its refit, if one comes, rounds them then (Bvh::refit_vertices()).
  const bool round = !b.refit_pending;
  const std::size_t n = vertices.size();
  std::vector<std::size_t>& first_bad = w.part_bad;
  std::vector<Aabb>& boxes = w.part_boxes;
  first_bad.assign(parts, n);
  boxes.assign(parts, Aabb{});
  w.in_parts(parts, [&](std::size_t k) {
    boxes[k] = b.tree.load_vertices(vertices, copy, n * k / parts, n * (k + 1) / parts, first_bad[k], round);
  });
  b.points_loaded = false;
  std::size_t v = n;  // the first part's bad vertex (each part's is its end when it has none)
  for (std::size_t k = parts; k-- > 0;)
    if (first_bad[k] < n * (k + 1) / parts) v = first_bad[k];
  if (v < n)
    throw std::invalid_argument("peelcd::World::set_vertices(): " + label_of(b.name, id) + ": vertex " +
                                std::to_string(v) + " " + coordinate_problem(vertices[v], false));
  Aabb box;
  for (std::size_t k = 0; k < parts; ++k) box.lo = box.lo.cwiseMin(boxes[k].lo), box.hi = box.hi.cwiseMax(boxes[k].hi);
  b.loaded_box = box;
  b.points_loaded = true;
  b.points_rounded = round;
}
}  // namespace

std::size_t World::Impl::vertex_parts(std::size_t n) const {
  return n >= kSplitVertices && (pool || model_lanes) ? std::size_t(frame_lanes) : 1;
}

void World::set_vertices(BodyId id, const std::vector<Vec3>& vertices) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_vertices");
  check_count(b, id, vertices);
  b.spare_vertices.resize(vertices.size());
  load_vertices(*impl_, b, id, vertices, b.spare_vertices.data(), impl_->vertex_parts(vertices.size()));
  b.mesh.vertices.swap(b.spare_vertices);
  b.refit_pending = true;
}

void World::set_vertices(BodyId id, std::vector<Vec3>&& vertices) {
  const ExclusiveUse exclusive(impl_->owner, "peelcd::World");
  Body& b = impl_->body(id, "set_vertices");
  check_count(b, id, vertices);
  load_vertices(*impl_, b, id, vertices, nullptr, impl_->vertex_parts(vertices.size()));
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
  b.points_loaded = false;  // (a pending refit rounds them all again)
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
  b.refit_pending = b.points_loaded = false;
  b.spare_vertices = {};
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
// Every public entry takes the guard, readers too: a reader running beside another thread's frame
// or change would read a body or a result while it is rewritten.
#define PEELCD_WORLD_GUARD const ExclusiveUse exclusive(impl_->owner, "peelcd::World")
bool World::self(BodyId id) const {
  PEELCD_WORLD_GUARD;
  return impl_->body(id).self;
}
bool World::contains(BodyId id) const {
  PEELCD_WORLD_GUARD;
  return id < impl_->bodies.size() && impl_->bodies[id].alive;
}
std::size_t World::size() const {
  PEELCD_WORLD_GUARD;
  return impl_->alive;
}
std::optional<BodyId> World::find(const std::string& name) const {
  PEELCD_WORLD_GUARD;
  const auto it = impl_->names.find(name);
  if (it == impl_->names.end()) return std::nullopt;
  return it->second;
}
const std::string& World::name(BodyId id) const {
  PEELCD_WORLD_GUARD;
  return impl_->body(id).name;
}
bool World::rigid(BodyId id) const {
  PEELCD_WORLD_GUARD;
  return impl_->body(id).is_rigid;
}
const Mesh& World::mesh(BodyId id) const {
  PEELCD_WORLD_GUARD;
  return impl_->body(id).local();
}
const Bvh& World::tree(BodyId id) const {
  PEELCD_WORLD_GUARD;
  Body& b = impl_->body(id, "tree");
  impl_->refit_now(b);
  return b.tree;
}
const WorldStats& World::stats() const {
  PEELCD_WORLD_GUARD;
  return impl_->stats;
}
ImageStage& World::stage() {
  PEELCD_WORLD_GUARD;
  return *impl_->stage;
}
void World::model_lanes(unsigned lanes) {
  PEELCD_WORLD_GUARD;
  impl_->model_lanes = lanes >= 2 ? std::min(lanes, Impl::kMaxModelLanes) : 0;
  impl_->model_loops.clear();
  impl_->model_done = true;
  impl_->stats.model_ms = 0.0;
}
const std::vector<LaneLoop>& World::lane_loops() const {
  PEELCD_WORLD_GUARD;
  return impl_->model_loops;
}
void World::batch_image_pairs(std::optional<bool> together) {
  PEELCD_WORLD_GUARD;
  impl_->batch_pairs = together;
}

void World::time_routes(std::optional<bool> timed) {
  PEELCD_WORLD_GUARD;
  impl_->time_routes_opt = timed;
  impl_->route_timer = RouteTimer{};
  impl_->routes_timed.reset();
}

bool World::comparing_routes() const {
  PEELCD_WORLD_GUARD;
  // Before a frame: whether routes will be timed where the options allow it; after one: whether
  // they were in the last frame (a margin, point sampling or views one at a time do not time them).
  const bool timed = impl_->routes_timed ? *impl_->routes_timed
                                         : impl_->time_routes_opt ? *impl_->time_routes_opt : !impl_->stage->runs_on_cpu();
  return timed && impl_->route_timer.comparing();
}

Mesh World::world_mesh(BodyId id) const {
  PEELCD_WORLD_GUARD;
  const Body& b = impl_->body(id);
  Mesh m = b.local();
  if (b.is_rigid)
    for (std::uint32_t v = 0; v < m.vertices.size(); ++v) m.vertices[v] = b.pose * b.shape->vertices[v];
  return m;
}

const FrameResult& World::collide(const DetectOptions& options) {
  PEELCD_WORLD_GUARD;
  impl_->collide(options, impl_->result);
  return impl_->result;
}

void World::collide(const DetectOptions& options, FrameResult& out) {
  PEELCD_WORLD_GUARD;
  impl_->collide(options, out);
}
#undef PEELCD_WORLD_GUARD

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
