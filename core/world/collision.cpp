#include "peelcd/core/world/collision.h"
#include "peelcd/core/exclusive_use.h"

#include "peelcd/core/world/world.h"

#include <stdexcept>

namespace peelcd {

CollisionGeometry::CollisionGeometry(Mesh mesh, std::string name) : name_(std::move(name)) {
  Object probe;
  probe.name = name_;
  probe.mesh = std::move(mesh);
  validate_object(probe, name_.empty() ? std::string("a CollisionGeometry") : "object '" + name_ + "'", false);
  mesh_ = std::make_shared<const Mesh>(std::move(probe.mesh));
}

CollisionObject::CollisionObject(std::shared_ptr<const CollisionGeometry> geometry, const Eigen::Affine3d& pose,
                                 std::string name)
    : geometry_(std::move(geometry)) {
  if (!geometry_) throw std::invalid_argument("peelcd::CollisionObject: no geometry");
  object_.name = name.empty() ? geometry_->name() : std::move(name);
  object_.mesh.triangles = geometry_->mesh().triangles;
  object_.rigid = RigidMotion{geometry_->shared_mesh(), Eigen::Affine3d::Identity()};
  set_pose(pose);
}

CollisionObject CollisionObject::deforming(Mesh mesh, std::string name) {
  CollisionObject o;
  o.object_.name = std::move(name);
  o.object_.mesh = std::move(mesh);
  o.stale_ = false;
  return o;
}

void CollisionObject::set_pose(const Eigen::Affine3d& pose) {
  if (!rigid()) throw std::logic_error("peelcd::CollisionObject::set_pose(): '" + object_.name + "' is deforming");
  if (const std::string problem = pose_problem(pose); !problem.empty())
    throw std::invalid_argument("peelcd::CollisionObject::set_pose(): '" + object_.name + "': the pose " + problem);
  object_.rigid->pose = pose;
  stale_ = true;
}

const Eigen::Affine3d& CollisionObject::pose() const {
  if (!rigid()) throw std::logic_error("peelcd::CollisionObject::pose(): '" + object_.name + "' is deforming");
  return object_.rigid->pose;
}

std::vector<Vec3>& CollisionObject::deforming_vertices() { return deforming_mesh().vertices; }

Mesh& CollisionObject::deforming_mesh() {
  if (rigid()) throw std::logic_error("peelcd::CollisionObject: '" + object_.name + "' is rigid: set its pose");
  return object_.mesh;
}

const Object& CollisionObject::world() const {
  if (rigid() && stale_) {
    const Mesh& local = geometry_->mesh();
    const Eigen::Affine3d& pose = object_.rigid->pose;
    object_.mesh.vertices.resize(local.vertices.size());
    for (std::size_t i = 0; i < local.vertices.size(); ++i) object_.mesh.vertices[i] = pose * local.vertices[i];
    stale_ = false;
  }
  return object_;
}

std::size_t collide(Detector& detector, const CollisionObject& a, const CollisionObject& b,
                    const CollisionRequest& request, CollisionResult& result) {
  result.clear();
  const std::vector<const Object*> objects = {&a.world(), &b.world()};
  FrameResult frame;
  detector.detect(objects, request.options, frame);
  result.timings = frame.timings;
  if (!frame.pairs.empty()) {
    result.pair = std::move(frame.pairs[0]);
    result.contacts = result.pair.colliding;
  }
  return result.contacts.size();
}

std::size_t collide(Detector& detector, const Mesh& a, const Eigen::Affine3d& pose_a, const Mesh& b,
                    const Eigen::Affine3d& pose_b, const CollisionRequest& request, CollisionResult& result) {
  // Poses first, named as this call's arguments (not as CollisionObject::set_pose()).
  for (const auto& [pose, name] : {std::pair<const Eigen::Affine3d*, const char*>{&pose_a, "pose_a"}, {&pose_b, "pose_b"}})
    if (const std::string problem = pose_problem(*pose); !problem.empty())
      throw std::invalid_argument(std::string("peelcd::collide(): ") + name + " " + problem);
  const auto ga = std::make_shared<const CollisionGeometry>(a, "a");
  const auto gb = std::make_shared<const CollisionGeometry>(b, "b");
  return collide(detector, CollisionObject(ga, pose_a), CollisionObject(gb, pose_b), request, result);
}

CollisionWorld::CollisionWorld(std::shared_ptr<Detector> detector) : detector_(std::move(detector)) {
  if (!detector_) throw std::invalid_argument("peelcd::CollisionWorld: no detector");
}

void CollisionWorld::add(CollisionObject* object) {
  const ExclusiveUse exclusive(owner_, "peelcd::CollisionWorld");
  if (!object) throw std::invalid_argument("peelcd::CollisionWorld::add(): a null object");
  objects_.push_back(object);
}

CollisionWorld::~CollisionWorld() = default;

void CollisionWorld::clear() {
  const ExclusiveUse exclusive(owner_, "peelcd::CollisionWorld");
  objects_.clear();
  bodies_.clear();
  world_.reset();
}

const FrameResult& CollisionWorld::detect(const DetectOptions& options) {
  const ExclusiveUse exclusive(owner_, "peelcd::CollisionWorld");
  if (!world_) world_ = std::make_unique<World>(detector_->stage_ptr());
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const CollisionObject& o = *objects_[i];
    if (i == bodies_.size()) {  // added since the last frame
      bodies_.push_back(o.rigid() ? world_->add_rigid(o.geometry()->shared_mesh(), o.pose(), o.name())
                                  : world_->add_deforming(o.world().mesh, o.name()));
      continue;
    }
    if (o.rigid()) {
      world_->set_pose(bodies_[i], o.pose());
    } else if (o.world().mesh.triangles == world_->mesh(bodies_[i]).triangles) {
      world_->set_vertices(bodies_[i], o.world().mesh.vertices);
    } else {  // fractured: a new topology
      world_->set_mesh(bodies_[i], o.world().mesh);
    }
  }
  world_->collide(options, result_);
  return result_;
}

}  // namespace peelcd
