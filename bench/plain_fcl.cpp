// A plain FCL 0.7 user's setup, written from FCL's documentation and tests alone and sharing no
// setup code with FclPeer (bench/peers.cpp): it holds the bench's FCL rows against what a user
// would write (`peelcd bench --audit`; docs/performance.md, "The peers").
//
// Per object an fcl::CollisionObjectd over an fcl::BVHModel<fcl::OBBRSSd> (the bounding volume
// FCL's documentation recommends for meshes): a rigid object's model, in its shape's
// coordinates, shared by the objects of that shape, built once and placed by the object's
// transform; any other object's model in world space, updated through FCL's update API
// (beginUpdateModel(), updateSubModel(), endUpdateModel(refit, bottom-up), then
// computeLocalAABB(): the update leaves the model's box as it was built, and the broad phase reads
// that box) when its vertices change, and built again when its triangles change. All objects in one
// DynamicAABBTreeCollisionManagerd (registered once, update() every frame); its collide() calls
// back with each pair whose boxes overlap, and fcl::collide on the pair with a request for every
// contact (no contact geometry) gives the triangle pairs (Contact::b1, b2). FCL's own triangle
// test decides. Self pairs are not set up.
#include "plain_setups.h"

#include "peelcd/core/clock.h"
#include "peelcd/core/pairs.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include <algorithm>
#include <limits>
#include <map>

namespace peelcd::bench {

namespace {

struct FclSetup final : PlainPeer::Impl {
  using Model = fcl::BVHModel<fcl::OBBRSSd>;
  struct Item {
    std::shared_ptr<Model> model;
    const Mesh* rigid_shape = nullptr;
    std::size_t triangles = 0, vertices = 0;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  std::vector<Item> items;
  std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<Model>>> shapes;
  fcl::DynamicAABBTreeCollisionManagerd manager;
  std::vector<fcl::Vector3d> points;

  static std::shared_ptr<Model> build(const Mesh& m) {
    std::vector<fcl::Vector3d> v(m.vertices.begin(), m.vertices.end());
    std::vector<fcl::Triangle> t;
    t.reserve(m.triangles.size());
    for (const Tri& x : m.triangles) t.emplace_back(x[0], x[1], x[2]);
    auto model = std::make_shared<Model>();
    model->beginModel(int(t.size()), int(v.size()));
    model->addSubModel(v, t);
    model->endModel();
    return model;
  }

  // The object's model and transform; true when the manager must be told of a new object.
  bool sync(Item& it, const Object& o, std::size_t index) {
    std::shared_ptr<Model> model = it.model;
    fcl::Transform3d pose = fcl::Transform3d::Identity();
    if (placed_rigid(o)) {
      auto& slot = shapes[o.rigid->shape.get()];
      if (slot.first != o.rigid->shape) {
        slot.first = o.rigid->shape;
        slot.second = build(*o.rigid->shape);
        ++builds;
      }
      model = slot.second;
      it.rigid_shape = o.rigid->shape.get();
      pose.linear() = o.rigid->pose.linear();
      pose.translation() = o.rigid->pose.translation();
    } else if (!it.model || it.rigid_shape || it.triangles != o.mesh.triangles.size() ||
               it.vertices != o.mesh.vertices.size()) {
      model = build(o.mesh);
      it.rigid_shape = nullptr, it.triangles = o.mesh.triangles.size(), it.vertices = o.mesh.vertices.size();
      ++builds;
    } else {
      bool changed = false;
      for (std::size_t k = 0; k < o.mesh.vertices.size() && !changed; ++k) changed = model->vertices[k] != o.mesh.vertices[k];
      if (changed) {
        points.assign(o.mesh.vertices.begin(), o.mesh.vertices.end());
        model->beginUpdateModel();
        model->updateSubModel(points);
        model->endUpdateModel(true, true);
        model->computeLocalAABB();  // endUpdateModel() leaves the box the broad phase reads as built
        ++refits;
      }
    }
    const bool added = !it.object || model != it.model;
    if (added) {
      if (it.object) manager.unregisterObject(it.object.get());
      it.object = std::make_unique<fcl::CollisionObjectd>(model, pose);
      it.object->setUserData(reinterpret_cast<void*>(index));
      it.model = model;
    } else {
      it.object->setTransform(pose);
    }
    it.object->computeAABB();
    return added;
  }

  std::string setup() const override {
    return "FCL 0.7 as written from its documentation and tests alone (bench/plain_fcl.cpp): one BVHModel<OBBRSS> "
           "per rigid shape placed by its transform or per other object in world space, updated by "
           "beginUpdateModel/updateSubModel/endUpdateModel and computeLocalAABB when its vertices change; DynamicAABBTreeCollisionManager, "
           "fcl::collide on each of its pairs asking for every contact; test: FCL's own; threads 1";
  }
  PeerFrame frame(const std::vector<Object>& objects) override;
};

struct Gather {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>>* hits;
  fcl::CollisionRequestd request;
};
bool on_pair(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  Gather& g = *static_cast<Gather*>(data);
  fcl::CollisionResultd result;
  fcl::collide(o1, o2, g.request, result);
  if (!result.isCollision()) return false;
  const auto a = reinterpret_cast<std::size_t>(o1->getUserData()), b = reinterpret_cast<std::size_t>(o2->getUserData());
  std::vector<std::uint64_t>& out = (*g.hits)[{std::min(a, b), std::max(a, b)}];
  for (std::size_t i = 0; i < result.numContacts(); ++i) {
    const fcl::Contactd& c = result.getContact(i);
    out.push_back(a < b ? pack_pair(std::uint32_t(c.b1), std::uint32_t(c.b2))
                        : pack_pair(std::uint32_t(c.b2), std::uint32_t(c.b1)));
  }
  return false;  // not done: every pair
}

PeerFrame FclSetup::frame(const std::vector<Object>& objects) {
  FclSetup& m = *this;
  PeerFrame f;
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>> hits;
  const auto t0 = Clock::now();
  if (m.items.size() != objects.size()) {
    m.manager.clear();
    m.items = std::vector<Item>(objects.size());
  }
  std::vector<fcl::CollisionObjectd*> added;
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (m.sync(m.items[i], objects[i], i)) added.push_back(m.items[i].object.get());
  if (!added.empty()) m.manager.registerObjects(added);
  m.manager.update();
  Gather g{&hits, fcl::CollisionRequestd(std::numeric_limits<std::size_t>::max(), false)};
  m.manager.collide(&g, &on_pair);
  f.ms = ms_since(t0);
  take_hits(hits, f);
  return f;
}

}  // namespace

std::unique_ptr<PlainPeer::Impl> plain_fcl() { return std::make_unique<FclSetup>(); }

}  // namespace peelcd::bench
