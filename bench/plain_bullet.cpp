// A plain Bullet 3 user's setup, written from Bullet's documentation and its GImpact demo alone
// and sharing no setup code with BulletPeer (bench/float_peers.cpp): it holds the bench's Bullet
// row against what a user would write (`peelcd bench --audit`; docs/performance.md, "The peers").
//
// A btCollisionWorld (btDefaultCollisionConfiguration, btCollisionDispatcher, btDbvtBroadphase)
// with GImpact's algorithm registered (btGImpactCollisionAlgorithm::registerAlgorithm). Per
// object a btCollisionObject holding a btGImpactMeshShape (margin 0) over a
// btTriangleIndexVertexArray: a rigid object's shape, in its own coordinates, shared by the
// objects of that shape, built once and placed by the object's world transform; any other object's
// world-space vertices, its shape refitted (postUpdate(), updateBound()) when they change, made
// again when they leave the range its box set was quantized over (a refit clamps to that range),
// and built again when its triangles change. Every object in the default filter group, colliding
// with all. Each frame: performDiscreteCollisionDetection() (the broad phase's pairs, then
// GImpact's own traversal and triangle test on each); the triangle pairs come from the
// contact-added callback (gContactAddedCallback, enabled per object by
// CF_CUSTOM_MATERIAL_CALLBACK: the documented way to learn which triangles touched), a pair per
// contact point, kept per object pair. Bullet's own triangle test (a clipping test with contact
// points) decides, so its misses and false pairs are its own. Self pairs are not set up.
#include "plain_setups.h"

#include "peelcd/core/clock.h"
#include "peelcd/core/pairs.h"

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btScalar.h>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace peelcd::bench {

namespace {

// What the contact-added callback appends to (one frame of one plain Bullet setup at a time: the
// callback is a global of Bullet's).
struct Sink {
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>>* hits = nullptr;
};
Sink g_sink;

bool contact_added(btManifoldPoint&, const btCollisionObjectWrapper* w0, int, int index0,
                   const btCollisionObjectWrapper* w1, int, int index1) {
  if (!g_sink.hits) return false;
  int a = w0->getCollisionObject()->getUserIndex(), b = w1->getCollisionObject()->getUserIndex();
  if (a > b) std::swap(a, b), std::swap(index0, index1);
  (*g_sink.hits)[{std::size_t(a), std::size_t(b)}].push_back(pack_pair(std::uint32_t(index0), std::uint32_t(index1)));
  return false;  // the contact point is not modified
}

struct BulletSetup final : PlainPeer::Impl {
  struct Shape {
    std::vector<float> v;
    std::vector<int> t;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;
    float lo[3], hi[3];  // the vertices' bounds at the box set's build, grown by 1 as its quantization is
    void build(const Mesh& m) {
      v.resize(3 * m.vertices.size());
      for (std::size_t i = 0; i < m.vertices.size(); ++i)
        for (int d = 0; d < 3; ++d) v[3 * i + std::size_t(d)] = float(m.vertices[i][d]);
      t.resize(3 * m.triangles.size());
      for (std::size_t i = 0; i < m.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) t[3 * i + std::size_t(k)] = int(m.triangles[i][k]);
      array = std::make_unique<btTriangleIndexVertexArray>(int(m.triangles.size()), t.data(), 3 * int(sizeof(int)),
                                                           int(m.vertices.size()), v.data(), 3 * int(sizeof(float)));
      make_shape();
    }
    void make_shape() {
      shape = std::make_unique<btGImpactMeshShape>(array.get());
      shape->setMargin(0.0f);
      shape->updateBound();
      for (int d = 0; d < 3; ++d) lo[d] = INFINITY, hi[d] = -INFINITY;
      for (std::size_t i = 0; i < v.size(); i += 3)
        for (int d = 0; d < 3; ++d)
          lo[d] = std::min(lo[d], v[i + std::size_t(d)]), hi[d] = std::max(hi[d], v[i + std::size_t(d)]);
      for (int d = 0; d < 3; ++d) lo[d] -= 1.0f, hi[d] += 1.0f;
    }
    bool within_build() const {
      for (std::size_t i = 0; i < v.size(); i += 3)
        for (int d = 0; d < 3; ++d)
          if (v[i + std::size_t(d)] < lo[d] || v[i + std::size_t(d)] > hi[d]) return false;
      return true;
    }
  };
  struct Item {
    std::unique_ptr<btCollisionObject> object;
    std::shared_ptr<Shape> shape;      // the object's own (world space) or its rigid shape's
    const Mesh* rigid_shape = nullptr;  // the shape's mesh when rigid
  };
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
  std::vector<Item> items;
  std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<Shape>>> shapes;

  BulletSetup() { btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher); }
  ~BulletSetup() override { clear(); }

  void clear() {
    for (Item& it : items)
      if (it.object) world.removeCollisionObject(it.object.get());
    items.clear();
  }

  static btTransform transform_of(const Eigen::Affine3d& p) {
    const Eigen::Matrix3d r = p.linear();
    const Vec3 o = p.translation();
    return btTransform(btMatrix3x3(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)), btScalar(r(1, 0)),
                                   btScalar(r(1, 1)), btScalar(r(1, 2)), btScalar(r(2, 0)), btScalar(r(2, 1)),
                                   btScalar(r(2, 2))),
                       btVector3(btScalar(o.x()), btScalar(o.y()), btScalar(o.z())));
  }

  // Sets the object's shape (attaching it to the world the first time) and transform.
  void place(std::size_t i, Item& it, btCollisionShape* shape, const btTransform& transform) {
    if (!it.object) {
      it.object = std::make_unique<btCollisionObject>();
      it.object->setUserIndex(int(i));
      it.object->setCollisionShape(shape);
      it.object->setWorldTransform(transform);
      it.object->setCollisionFlags(btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);  // not static: pairs with all
      world.addCollisionObject(it.object.get(), btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter);
    } else {
      if (it.object->getCollisionShape() != shape) it.object->setCollisionShape(shape);
      it.object->setWorldTransform(transform);
    }
  }

  void sync(std::size_t i, const Object& o) {
    Item& it = items[i];
    if (placed_rigid(o)) {
      auto& slot = shapes[o.rigid->shape.get()];
      if (slot.first != o.rigid->shape) {
        slot.first = o.rigid->shape;
        slot.second = std::make_shared<Shape>();
        slot.second->build(*o.rigid->shape);
        ++builds;
      }
      it.shape = slot.second, it.rigid_shape = o.rigid->shape.get();
      place(i, it, it.shape->shape.get(), transform_of(o.rigid->pose));
      return;
    }
    const bool rebuild = !it.shape || it.rigid_shape || it.shape->t.size() != 3 * o.mesh.triangles.size() ||
                         it.shape->v.size() != 3 * o.mesh.vertices.size();
    if (rebuild) {
      it.shape = std::make_shared<Shape>();
      it.shape->build(o.mesh);
      it.rigid_shape = nullptr;
      ++builds;
    } else {
      bool changed = false;
      for (std::size_t k = 0; k < o.mesh.vertices.size(); ++k)
        for (int d = 0; d < 3; ++d) {
          const float x = float(o.mesh.vertices[k][d]);
          changed |= it.shape->v[3 * k + std::size_t(d)] != x;
          it.shape->v[3 * k + std::size_t(d)] = x;
        }
      if (changed && it.shape->within_build()) {  // postUpdate() then updateBound() refits
        it.shape->shape->postUpdate();
        it.shape->shape->updateBound();
        ++refits;
      } else if (changed) {
        // A refit clamps the boxes to the quantization range of the set's build (its vertices'
        // bounds grown by 1), so a mesh that travels beyond it finds nothing (the first thing a
        // user of a walking deforming mesh meets): a new shape over the same arrays.
        it.shape->make_shape();
        ++builds;
      }
    }
    place(i, it, it.shape->shape.get(), btTransform::getIdentity());
  }

  std::string setup() const override {
    return "Bullet " + std::to_string(BT_BULLET_VERSION) +
           " as written from its documentation and GImpact demo alone (bench/plain_bullet.cpp): a btCollisionWorld "
           "(btDbvtBroadphase) with btGImpactCollisionAlgorithm registered, one btGImpactMeshShape (margin 0) per rigid "
           "shape placed by its transform or per other object in world space, refitted when its vertices change (a new shape beyond its quantization range); "
           "performDiscreteCollisionDetection(), the triangle pairs from gContactAddedCallback; test: GImpact's own; "
           "threads 1";
  }
  PeerFrame frame(const std::vector<Object>& objects) override;
};

PeerFrame BulletSetup::frame(const std::vector<Object>& objects) {
  BulletSetup& m = *this;
  PeerFrame f;
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>> hits;
  const auto t0 = Clock::now();
  if (m.items.size() != objects.size()) {
    m.clear();
    m.items.resize(objects.size());
  }
  for (std::size_t i = 0; i < objects.size(); ++i) m.sync(i, objects[i]);
  {
    struct Hook {  // the callback and its sink set for this frame, put back however it ends
      ContactAddedCallback before = gContactAddedCallback;
      explicit Hook(std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>>* hits) {
        g_sink.hits = hits;
        gContactAddedCallback = &contact_added;
      }
      ~Hook() {
        gContactAddedCallback = before;
        g_sink.hits = nullptr;
      }
    } hook(&hits);
    m.world.performDiscreteCollisionDetection();
  }
  f.ms = ms_since(t0);
  take_hits(hits, f);
  return f;
}

}  // namespace

std::unique_ptr<PlainPeer::Impl> plain_bullet() { return std::make_unique<BulletSetup>(); }

}  // namespace peelcd::bench
