#include "peelcd/bench/peers.h"
#include "peelcd/core/clock.h"
#include "peer_util.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/worker_pool.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <map>

namespace peelcd::bench {

PeerFrame cgal_frame(const std::vector<Object>& objects, unsigned threads) {
  static thread_local std::unique_ptr<WorkerPool> pool;
  if (threads > 1 && (!pool || pool->lanes() != threads)) pool = std::make_unique<WorkerPool>(threads);
  PeerFrame f;
  const auto t0 = Clock::now();
  std::vector<Aabb> boxes;
  boxes.reserve(objects.size());
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  plan_object_pairs(boxes, objects, f);  // self pairs too: the exact self reference
  parallel_for(threads > 1 ? pool.get() : nullptr, f.objects.size(), [&](std::size_t i) {
    const auto [a, b] = f.objects[i];
    if (a == b) {
      f.per_pair[i] = exact_self_pairs(objects[a].mesh);
      return;
    }
    const Mesh& ma = objects[a].mesh;
    const Mesh& mb = objects[b].mesh;
    const Aabb roi = intersection(boxes[a], boxes[b]);
    std::vector<std::uint32_t> ta, tb;  // the crop: triangles touching the overlap box
    triangles_touching(ma, roi, ta);
    triangles_touching(mb, roi, tb);
    std::vector<std::uint64_t> candidates, hits;
    cgal_box_overlap_pairs(ma, ta, mb, tb, candidates);
    for (const std::uint64_t k : candidates)
      if (triangles_intersect(corners(ma, pair_a(k)), corners(mb, pair_b(k)))) hits.push_back(k);
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    f.per_pair[i] = std::move(hits);
  });
  for (const auto& p : f.per_pair) f.pairs += p.size();
  f.ms = ms_since(t0);
  return f;
}

struct FclPeer::Impl {
  using Oriented = fcl::BVHModel<fcl::OBBRSSd>;
  using Aligned = fcl::BVHModel<fcl::AABBd>;
  struct Entry {
    bool rigid = false;                     // rigid with an isometric pose: `oriented` kept
    std::shared_ptr<Oriented> oriented;     // rigid: built once from `shape`, in shape coordinates
    std::shared_ptr<const Mesh> shape;
    std::shared_ptr<Aligned> aligned;       // deforming, refit mode: the whole mesh, refitted
    std::shared_ptr<fcl::Boxd> box;         // deforming, rebuild mode: its bounds for the broad phase
    std::size_t triangles = 0, vertices = 0;
    std::unique_ptr<fcl::CollisionObjectd> object;
    std::size_t index = 0;
  };
  Deforming deforming;
  unsigned threads;
  std::unique_ptr<WorkerPool> pool;
  std::vector<Entry> entries;
  std::vector<Aabb> boxes;  // this frame's object boxes
  std::unique_ptr<fcl::DynamicAABBTreeCollisionManagerd> manager;
  std::atomic<std::size_t> builds{0}, refits{0}, pair_builds{0};
  // One oriented tree per rigid shape, shared by every object that moves it (FCL geometries
  // may be shared by collision objects).
  std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<Oriented>>> shared;
  std::vector<fcl::Vector3d> points;

  template <class Model>
  static std::shared_ptr<Model> build(const Mesh& mesh, const std::vector<std::uint32_t>* only = nullptr) {
    auto m = std::make_shared<Model>();
    std::vector<fcl::Vector3d> v;
    std::vector<fcl::Triangle> t;
    if (!only) {
      v.assign(mesh.vertices.begin(), mesh.vertices.end());
      t.reserve(mesh.triangles.size());
      for (const Tri& tri : mesh.triangles) t.emplace_back(tri[0], tri[1], tri[2]);
    } else {  // the listed triangles, their vertices compacted
      std::vector<int> slot(mesh.vertices.size(), -1);
      t.reserve(only->size());
      for (const std::uint32_t f : *only) {
        std::size_t c[3];
        for (int k = 0; k < 3; ++k) {
          int& s = slot[mesh.triangles[f][k]];
          if (s < 0) {
            s = int(v.size());
            v.push_back(mesh.vertices[mesh.triangles[f][k]]);
          }
          c[k] = std::size_t(s);
        }
        t.emplace_back(c[0], c[1], c[2]);
      }
    }
    m->beginModel(int(t.size()), int(v.size()));
    m->addSubModel(v, t);
    m->endModel();
    m->computeLocalAABB();
    return m;
  }

  // A pose FCL can use: a rotation and a translation (FCL's transforms are isometries).
  static bool isometry(const Eigen::Affine3d& pose) {
    const Eigen::Matrix3d r = pose.linear();
    return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12;
  }

  // Brings entry i up to date with object o; true when its collision object was replaced.
  bool update(std::size_t i, const Object& o) {
    Entry& e = entries[i];
    e.index = i;
    std::shared_ptr<fcl::CollisionGeometryd> geometry;
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    // Static (rigid at the identity pose): its world-space AABB tree built once, never refitted.
    const bool fixed = o.rigid && o.rigid->shape && o.rigid->pose.matrix().isIdentity(0.0);
    const bool rigid = !fixed && o.rigid && o.rigid->shape && isometry(o.rigid->pose);
    bool replaced = false;
    e.rigid = rigid;
    if (rigid) {
      e.aligned.reset();
      e.box.reset();
      if (e.shape != o.rigid->shape || !e.oriented) {  // built once per shape
        auto& slot = shared[o.rigid->shape.get()];
        if (slot.first != o.rigid->shape) {
          slot = {o.rigid->shape, build<Oriented>(*o.rigid->shape)};
          ++builds;
        }
        e.oriented = slot.second;
        e.shape = o.rigid->shape;
        replaced = true;
      }
      geometry = e.oriented;
      tf.linear() = o.rigid->pose.linear();
      tf.translation() = o.rigid->pose.translation();
    } else if (fixed) {
      e.oriented.reset();
      e.box.reset();
      if (e.shape != o.rigid->shape || !e.aligned) {
        e.aligned = build<Aligned>(*o.rigid->shape);
        e.shape = o.rigid->shape;
        ++builds;
        replaced = true;
      }
      geometry = e.aligned;
    } else if (deforming == Deforming::refit) {
      e.oriented.reset();
      e.shape.reset();
      e.box.reset();
      if (e.aligned && e.triangles == o.mesh.triangles.size() && e.vertices == o.mesh.vertices.size()) {
        points.assign(o.mesh.vertices.begin(), o.mesh.vertices.end());
        e.aligned->beginUpdateModel();
        e.aligned->updateSubModel(points);
        e.aligned->endUpdateModel(true, true);
        e.aligned->computeLocalAABB();
        ++refits;
      } else {
        e.aligned = build<Aligned>(o.mesh);
        ++builds;
        replaced = true;
      }
      geometry = e.aligned;
    } else {  // rebuilt per pair after the broad phase, cropped: here only its bounds
      e.oriented.reset();
      e.shape.reset();
      e.aligned.reset();
      const Aabb& b = boxes[i];
      const Vec3 side = (b.hi - b.lo).cwiseMax(Vec3::Constant(1e-12));
      if (!e.box) e.box = std::make_shared<fcl::Boxd>(side);
      e.box->side = side;
      e.box->computeLocalAABB();
      geometry = e.box;
      tf.translation() = 0.5 * (b.lo + b.hi);
    }
    e.triangles = o.mesh.triangles.size();
    e.vertices = o.mesh.vertices.size();
    if (replaced || !e.object || e.object->collisionGeometry() != geometry) {
      replaced = true;
      e.object = std::make_unique<fcl::CollisionObjectd>(geometry, tf);
      e.object->setUserData(&e);
    } else {
      e.object->setTransform(tf);
    }
    e.object->computeAABB();
    return replaced;
  }

  // Every colliding triangle pair of objects a and b (packed, sorted, distinct).
  std::vector<std::uint64_t> narrow(const std::vector<Object>& objects, std::size_t a, std::size_t b) {
    const Entry& ea = entries[a];
    const Entry& eb = entries[b];
    fcl::CollisionRequestd request(std::numeric_limits<std::size_t>::max() / 2, false);
    fcl::CollisionResultd result;
    std::vector<std::uint32_t> ta, tb;  // cropped triangles (third kind below)
    if (ea.rigid && eb.rigid) {
      // Both rigid: the oriented traversal with their poses (no copy, no refit).
      fcl::detail::MeshCollisionTraversalNodeOBBRSS<double> node;
      fcl::detail::initialize(node, *ea.oriented, ea.object->getTransform(), *eb.oriented, eb.object->getTransform(),
                              request, result);
      fcl::detail::collide(&node);
    } else {
      // Both deforming and refitted: their world-space AABB trees. Otherwise (rebuild mode, or
      // a rigid object against a deforming one): AABB trees of the triangles touching the
      // overlap box, built now.
      std::shared_ptr<Aligned> ma = ea.aligned, mb = eb.aligned;
      const bool crop = !(ma && mb);
      if (crop) {
        const Aabb roi = intersection(boxes[a], boxes[b]);
        triangles_touching(objects[a].mesh, roi, ta);
        triangles_touching(objects[b].mesh, roi, tb);
        if (ta.empty() || tb.empty()) return {};
        ma = build<Aligned>(objects[a].mesh, &ta);
        mb = build<Aligned>(objects[b].mesh, &tb);
        pair_builds += 2;
      }
      // What fcl::collide() does for two AABB trees, minus its copy of both models (Debian's
      // FCL 0.7 frees that copy with a mismatched deallocator, which AddressSanitizer aborts
      // on; leaving the copy out only makes the peer faster). World coordinates, identity
      // transforms: initialize() leaves the models as they are.
      fcl::detail::MeshCollisionTraversalNode<fcl::AABBd> node;
      fcl::Transform3d tf_a = fcl::Transform3d::Identity(), tf_b = fcl::Transform3d::Identity();
      fcl::detail::initialize(node, *ma, tf_a, *mb, tf_b, request, result);
      fcl::detail::collide(&node);
      if (!crop) ta.clear(), tb.clear();
    }
    std::vector<std::uint64_t> found;
    found.reserve(result.numContacts());
    for (std::size_t k = 0; k < result.numContacts(); ++k) {
      const auto& c = result.getContact(k);
      const auto ia = ta.empty() ? std::uint32_t(c.b1) : ta[std::size_t(c.b1)];
      const auto ib = tb.empty() ? std::uint32_t(c.b2) : tb[std::size_t(c.b2)];
      found.push_back(std::uint64_t(ia) << 32 | ib);
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
  }
};

FclPeer::FclPeer(Deforming deforming, unsigned threads) : impl_(std::make_unique<Impl>()) {
  impl_->deforming = deforming;
  impl_->threads = std::max(1u, threads);
  if (impl_->threads > 1) impl_->pool = std::make_unique<WorkerPool>(impl_->threads);
}
FclPeer::~FclPeer() = default;
std::size_t FclPeer::builds() const { return impl_->builds; }
std::size_t FclPeer::refits() const { return impl_->refits; }
std::size_t FclPeer::pair_builds() const { return impl_->pair_builds; }
std::string FclPeer::name() const {
  return impl_->deforming == Deforming::refit ? "FCL 0.7, deforming refit" : "FCL 0.7, deforming rebuilt cropped";
}
std::string FclPeer::column() const { return impl_->deforming == Deforming::refit ? "FCL refit" : "FCL build"; }
std::string FclPeer::setup() const {
  return std::string("FCL 0.7: object pairs from DynamicAABBTreeCollisionManager; two rigid objects: OBBRSS trees "
                     "built once from their shapes, moved by their poses; a static object: its AABB tree built once; ") +
         (impl_->deforming == Deforming::refit
              ? "two deforming objects: AABB trees of the world meshes refitted every frame (beginUpdateModel)"
              : "two deforming objects: AABB trees of the triangles touching the pair's overlap box, built per pair") +
         "; otherwise cropped AABB trees built per pair; every contact (CollisionRequest num_max_contacts unbounded), FCL's own triangle test; threads " +
         std::to_string(impl_->threads);
}

PeerFrame FclPeer::frame(const std::vector<Object>& objects) {
  Impl& s = *impl_;
  PeerFrame f;
  const auto t0 = Clock::now();
  bool reregister = s.entries.size() != objects.size() || !s.manager;
  if (s.entries.size() != objects.size()) s.entries.resize(objects.size());
  // The objects' world boxes, for the broad-phase boxes of rebuilt objects and the crops: made
  // where needed (a rigid object's box would read all its vertices every frame; FCL places it
  // by its pose).
  s.boxes.assign(objects.size(), Aabb{});
  std::vector<char> boxed(objects.size(), 0);
  auto box = [&](std::size_t i) {
    if (!boxed[i]) s.boxes[i] = bounds(objects[i].mesh), boxed[i] = 1;
  };
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const auto& r = objects[i].rigid;
    if (s.deforming == Deforming::rebuild &&
        !(r && r->shape && (r->pose.matrix().isIdentity(0.0) || Impl::isometry(r->pose))))
      box(i);  // update() gives it a box of these bounds for the broad phase
    reregister |= s.update(i, objects[i]);
  }
  if (reregister) {
    s.manager = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
    std::vector<fcl::CollisionObjectd*> all;
    for (Impl::Entry& e : s.entries) all.push_back(e.object.get());
    s.manager->registerObjects(all);
    s.manager->setup();
  } else {
    s.manager->update();
  }
  // FCL's broad phase: the object pairs whose (FCL) boxes overlap.
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  s.manager->collide(&pairs, [](fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
    auto* out = static_cast<std::vector<std::pair<std::size_t, std::size_t>>*>(data);
    const std::size_t a = static_cast<Impl::Entry*>(o1->getUserData())->index;
    const std::size_t b = static_cast<Impl::Entry*>(o2->getUserData())->index;
    out->emplace_back(std::min(a, b), std::max(a, b));
    return false;  // go on
  });
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [a, b] : pairs)
    if (!(s.entries[a].rigid && s.entries[b].rigid) && !(s.entries[a].aligned && s.entries[b].aligned)) box(a), box(b);
  f.objects = std::move(pairs);
  f.per_pair.resize(f.objects.size());
  parallel_for(s.pool.get(), f.objects.size(),
               [&](std::size_t i) { f.per_pair[i] = s.narrow(objects, f.objects[i].first, f.objects[i].second); });
  for (const auto& p : f.per_pair) f.pairs += p.size();
  f.ms = ms_since(t0);
  return f;
}

}  // namespace peelcd::bench
