#include "peelcd/bench/float_peers.h"
#include "peelcd/core/clock.h"
#include "peer_util.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/core/worker_pool.h"

#include <embree3/rtcore.h>

#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactQuantizedBvh.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace peelcd::bench {
// A named namespace: the peers' Impl classes (external linkage) hold these.
namespace float_peers_detail {

// A body's float geometry: vertices (x, y, z), triangles (3 indices), self adjacency.
struct FloatMesh {
  std::vector<float> v;
  std::vector<std::uint32_t> t;
  void corners(std::uint32_t f, std::array<float, 9>& out) const {
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) out[std::size_t(3 * k + c)] = v[3 * std::size_t(t[3 * std::size_t(f) + std::size_t(k)]) + std::size_t(c)];
  }
  void set_vertices(const std::vector<Vec3>& vs, const Eigen::Affine3d* pose = nullptr) {
    v.resize(3 * vs.size());
    for (std::size_t i = 0; i < vs.size(); ++i) {
      const Vec3 p = pose ? Vec3(*pose * vs[i]) : vs[i];
      v[3 * i] = float(p.x()), v[3 * i + 1] = float(p.y()), v[3 * i + 2] = float(p.z());
    }
  }
  void set_triangles(const std::vector<Tri>& ts) {
    t.resize(3 * ts.size());
    for (std::size_t i = 0; i < ts.size(); ++i)
      for (int k = 0; k < 3; ++k) t[3 * i + std::size_t(k)] = ts[i][std::size_t(k)];
  }
};

}  // namespace float_peers_detail
using float_peers_detail::FloatMesh;
namespace {

// The triangle pairs of one object pair, collected from a traversal's candidate batches (the
// float test; self: no triangle with itself, none sharing a vertex, each couple once).
struct Collector {
  const FloatMesh* a = nullptr;
  const FloatMesh* b = nullptr;
  const Mesh* self_mesh = nullptr;  // non-null: a self pair
  const std::vector<std::uint32_t>* rep = nullptr;
  bool move_b = false;  // B's corners mapped by `rel` (row-major 3 x 4) before the test
  float rel[12] = {};
  TriangleTest which = TriangleTest::moller;
  std::vector<std::uint64_t> hits;
  std::mutex mutex;
  // Filled by one thread (Bullet's lane): hits appended directly. Else (rtcCollide) a callback
  // may run on any of the library's threads: each keeps its buffer (no allocation per callback
  // once it has grown; rtcCollide calls back once per small batch of couples) and appends it
  // under the lock.
  bool serial = false;
  template <class Pairs>
  void test(const Pairs& pairs, std::size_t n) {
    thread_local std::vector<std::uint64_t> buffer;
    std::vector<std::uint64_t>& local = serial ? hits : buffer;
    if (!serial) local.clear();
    std::array<float, 9> ta, tb;
    for (std::size_t i = 0; i < n; ++i) {
      std::uint32_t x = pairs(i).first, y = pairs(i).second;
      if (self_mesh) {
        // A tree against itself reports each couple in both orders (Embree's rtcCollide and
        // GImpact's find_collision alike): the order with x < y is tested, once.
        if (x >= y) continue;
        if (triangles_adjacent(*self_mesh, *rep, x, y)) continue;
      }
      a->corners(x, ta);
      b->corners(y, tb);
      if (move_b)
        for (int k = 0; k < 9; k += 3) {
          const float x0 = tb[std::size_t(k)], x1 = tb[std::size_t(k + 1)], x2 = tb[std::size_t(k + 2)];
          for (int r = 0; r < 3; ++r)
            tb[std::size_t(k + r)] = rel[4 * r] * x0 + rel[4 * r + 1] * x1 + rel[4 * r + 2] * x2 + rel[4 * r + 3];
        }
      if (which == TriangleTest::moller ? tri_tri_moller(ta, tb) : tri_tri_float(ta, tb)) local.push_back(pack_pair(x, y));
    }
    if (serial || local.empty()) return;
    std::lock_guard<std::mutex> lock(mutex);
    hits.insert(hits.end(), local.begin(), local.end());
  }
  // The hits as found: sorted by sort_pairs() after the frame's clock stops (a user of the
  // library gets them unsorted; the bench's scoring wants them sorted).
  std::vector<std::uint64_t> take() { return std::move(hits); }
};

// Each pair's hits sorted and distinct, and the total (for scoring; outside the timed frame).
void sort_pairs(PeerFrame& f) {
  for (std::vector<std::uint64_t>& p : f.per_pair) {
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    f.pairs += p.size();
  }
}

bool same_pose(const Eigen::Affine3d& a, const Eigen::Affine3d& b) { return a.matrix() == b.matrix(); }

}  // namespace

// --- Embree --------------------------------------------------------------------------------

struct EmbreePeer::Impl {
  struct Body {
    RTCScene scene = nullptr;
    RTCGeometry geometry = nullptr;
    FloatMesh mesh;
    std::shared_ptr<const Mesh> shape;  // the rigid shape its vertices came from (or null)
    Eigen::Affine3d placed = Eigen::Affine3d::Identity();  // the pose its vertices were mapped by
    bool in_a_frame = false;            // two rigid objects: B's vertices in A's frame
    std::vector<std::uint32_t> rep;     // self adjacency (Object::self)
    std::size_t triangles = 0;
    bool dynamic = false;               // built for updates (refit or low-quality rebuild)
    ~Body() {
      if (scene) rtcReleaseScene(scene);
    }
  };
  Update update;
  unsigned threads;
  TriangleTest test = TriangleTest::moller;
  RTCDevice device = nullptr;
  std::unique_ptr<WorkerPool> pool;
  std::vector<std::unique_ptr<Body>> bodies;
  std::size_t builds = 0, refits = 0;

  static void bounds(const RTCBoundsFunctionArguments* args) {
    const auto* m = static_cast<const FloatMesh*>(args->geometryUserPtr);
    const std::uint32_t* t = &m->t[3 * std::size_t(args->primID)];
    const float* p0 = &m->v[3 * std::size_t(t[0])];
    const float* p1 = &m->v[3 * std::size_t(t[1])];
    const float* p2 = &m->v[3 * std::size_t(t[2])];
    RTCBounds* o = args->bounds_o;
    o->lower_x = std::min({p0[0], p1[0], p2[0]});
    o->lower_y = std::min({p0[1], p1[1], p2[1]});
    o->lower_z = std::min({p0[2], p1[2], p2[2]});
    o->upper_x = std::max({p0[0], p1[0], p2[0]});
    o->upper_y = std::max({p0[1], p1[1], p2[1]});
    o->upper_z = std::max({p0[2], p1[2], p2[2]});
  }

  static void collide(void* user, RTCCollision* c, unsigned n) {
    static_cast<Collector*>(user)->test(
        [c](std::size_t i) { return std::pair<std::uint32_t, std::uint32_t>(c[i].primID0, c[i].primID1); }, n);
  }

  // A new scene over `b.mesh` (already filled). Static (nothing will move it): Embree's
  // defaults, a static scene of medium quality, as its documentation sets up geometry that is
  // not updated. Dynamic: RTC_SCENE_FLAG_DYNAMIC under a low-quality scene, whose per-geometry
  // quality Embree honours (rtcSetGeometryBuildQuality(3)): REFIT to refit, LOW to rebuild
  // (Morton) at every commit, by the Update mode.
  void build(Body& b, bool dynamic) {
    if (b.scene) rtcReleaseScene(b.scene);
    b.scene = rtcNewScene(device);
    if (dynamic) {
      rtcSetSceneFlags(b.scene, RTC_SCENE_FLAG_DYNAMIC);
      rtcSetSceneBuildQuality(b.scene, RTC_BUILD_QUALITY_LOW);
    }
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, unsigned(b.mesh.t.size() / 3));
    rtcSetGeometryUserData(g, &b.mesh);
    rtcSetGeometryBoundsFunction(g, &Impl::bounds, nullptr);
    if (dynamic)
      rtcSetGeometryBuildQuality(g, update == Update::refit ? RTC_BUILD_QUALITY_REFIT : RTC_BUILD_QUALITY_LOW);
    rtcCommitGeometry(g);
    rtcAttachGeometry(b.scene, g);
    rtcReleaseGeometry(g);
    b.geometry = g;
    b.dynamic = dynamic;
    rtcCommitScene(b.scene);
    ++builds;
  }
  // A body whose vertices changed: a dynamic scene commits them (refit or rebuild); a static one
  // (a rigid body that had not moved) is built again as dynamic, once.
  void commit_moved(Body& b) {
    if (!b.dynamic) {
      build(b, true);
      return;
    }
    rtcCommitGeometry(b.geometry);
    rtcCommitScene(b.scene);
    ++refits;
  }

  // Brings body i to object o; `frame_of_a`: the pose of A in a two-rigid-object scene (B's
  // vertices mapped into A's frame), else null (world space).
  void sync(std::size_t i, const Object& o, const Eigen::Affine3d* frame_of_a, bool a_frame_root) {
    if (!bodies[i]) bodies[i] = std::make_unique<Body>();
    Body& b = *bodies[i];
    const bool topology = !b.scene || b.triangles != o.mesh.triangles.size();
    if (a_frame_root) {  // A in its own frame: its shape's vertices, built once
      if (topology || b.shape != o.rigid->shape || !b.in_a_frame) {
        b.mesh.set_vertices(o.rigid->shape->vertices);
        b.mesh.set_triangles(o.rigid->shape->triangles);
        b.shape = o.rigid->shape, b.in_a_frame = true, b.triangles = o.mesh.triangles.size();
        build(b, false);  // never moved: A's frame is the frame
      }
    } else if (frame_of_a) {  // B mapped into A's frame every frame its relative pose changes
      const Eigen::Affine3d rel = frame_of_a->inverse() * o.rigid->pose;
      const bool moved = !b.in_a_frame || b.shape != o.rigid->shape || !same_pose(rel, b.placed);
      if (topology || moved) {
        b.mesh.set_vertices(o.rigid->shape->vertices, &rel);
        b.placed = rel, b.shape = o.rigid->shape, b.in_a_frame = true;
        if (topology) {
          b.mesh.set_triangles(o.mesh.triangles);
          b.triangles = o.mesh.triangles.size();
          build(b, true);  // B moves in A's frame whenever the relative pose changes
        } else {
          commit_moved(b);
        }
      }
    } else {  // world space: untouched while a rigid object keeps its pose
      const bool rigid_still = o.rigid && o.rigid->shape && b.shape == o.rigid->shape && !b.in_a_frame &&
                               same_pose(o.rigid->pose, b.placed);
      if (topology || !rigid_still) {
        b.mesh.set_vertices(o.mesh.vertices);
        b.shape = o.rigid ? o.rigid->shape : nullptr;
        b.placed = o.rigid ? o.rigid->pose : Eigen::Affine3d::Identity();
        b.in_a_frame = false;
        if (topology) {
          b.mesh.set_triangles(o.mesh.triangles);
          b.triangles = o.mesh.triangles.size();
          build(b, !o.rigid);  // a deforming object moves; a rigid one is static until it does
        } else {
          commit_moved(b);  // refitted, or rebuilt at the scene's low quality (Update)
        }
      }
    }
    if (o.self && b.rep.size() != o.mesh.vertices.size()) vertex_representatives(o.mesh, SelfAdjacency::index, b.rep);
  }
};

EmbreePeer::EmbreePeer(Update update, unsigned threads, TriangleTest test) : impl_(std::make_unique<Impl>()) {
  impl_->update = update;
  impl_->test = test;
  impl_->threads = std::max(1u, threads);
  const std::string config = "threads=" + std::to_string(impl_->threads);
  impl_->device = rtcNewDevice(config.c_str());
  if (!impl_->device) throw std::runtime_error("Embree: rtcNewDevice failed");
  if (impl_->threads > 1) impl_->pool = std::make_unique<WorkerPool>(impl_->threads);
}
EmbreePeer::~EmbreePeer() {
  impl_->bodies.clear();
  if (impl_->device) rtcReleaseDevice(impl_->device);
}
std::size_t EmbreePeer::builds() const { return impl_->builds; }
std::string EmbreePeer::name() const {
  return std::string("Embree 3 rtcCollide, ") + (impl_->update == Update::refit ? "refit" : "rebuilt low") +
         (variant() ? ", scaled test" : "");
}
std::string EmbreePeer::column() const {
  return variant() ? "Embree sc" : impl_->update == Update::refit ? "Embree rf" : "Embree lo";
}
bool EmbreePeer::variant() const { return impl_->test != TriangleTest::moller; }
std::string EmbreePeer::setup() const {
  return std::string("Embree ") + std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
         std::to_string(RTC_VERSION_PATCH) + " rtcCollide: one user geometry per object (a primitive per triangle); " +
         "static objects: a static scene (default flags, medium quality); moving ones: a dynamic scene of low quality, " +
         (impl_->update == Update::refit ? "geometry quality REFIT (refit)" : "geometry quality LOW (Morton rebuild)") +
         "; a rigid pair: A's scene in A's frame, B mapped into it; test " + to_string(impl_->test) + "; threads " +
         std::to_string(impl_->threads);
}
std::size_t EmbreePeer::refits() const { return impl_->refits; }

PeerFrame EmbreePeer::frame(const std::vector<Object>& objects) {
  Impl& m = *impl_;
  PeerFrame f;
  const auto t0 = Clock::now();
  m.bodies.resize(objects.size());
  const bool rigid_pair = objects.size() == 2 && objects[0].rigid && objects[0].rigid->shape && objects[1].rigid &&
                          objects[1].rigid->shape;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (rigid_pair)
      m.sync(i, objects[i], i == 1 ? &objects[0].rigid->pose : nullptr, i == 0);
    else
      m.sync(i, objects[i], nullptr, false);
  }
  // Object pairs: the scenes' own bounds (in one frame: world, or A's for a rigid pair).
  std::vector<Aabb> boxes(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    RTCBounds bb;
    rtcGetSceneBounds(m.bodies[i]->scene, &bb);
    boxes[i].lo = Vec3(bb.lower_x, bb.lower_y, bb.lower_z);
    boxes[i].hi = Vec3(bb.upper_x, bb.upper_y, bb.upper_z);
  }
  plan_object_pairs(boxes, objects, f);
  parallel_for(m.pool.get(), f.objects.size(), [&](std::size_t k) {
    const auto [a, b] = f.objects[k];
    Collector c;
    c.which = m.test;
    // (never serial: rtcCollide may call back from several of TBB's threads, even on a device
    // of one thread once another device in the process asked for more)
    c.a = &m.bodies[a]->mesh;
    c.b = &m.bodies[b]->mesh;
    if (a == b) c.self_mesh = &objects[a].mesh, c.rep = &m.bodies[a]->rep;
    rtcCollide(m.bodies[a]->scene, m.bodies[b]->scene, &Impl::collide, &c);
    f.per_pair[k] = c.take();
  });
  f.ms = ms_since(t0);
  sort_pairs(f);
  return f;
}

// --- Bullet --------------------------------------------------------------------------------

struct BulletPeer::Impl {
  struct Shape {
    FloatMesh mesh;                     // btScalar is float in Debian's libbullet-dev
    std::vector<int> indices;           // Bullet's index type
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;
    std::size_t triangles = 0, vertices = 0;
    // The quantized box set's range, fixed when it is built: the vertices' bounds grown by
    // Bullet's quantization margin (btQuantizedBvhTree::calc_quantization's 1.0). A refit
    // clamps boxes to it, so vertices that leave it need the set built again.
    Vec3 range_lo, range_hi;
    bool within_range() const {
      for (std::size_t i = 0; i < mesh.v.size(); i += 3)
        for (int c = 0; c < 3; ++c)
          if (mesh.v[i + std::size_t(c)] < range_lo[c] || mesh.v[i + std::size_t(c)] > range_hi[c]) return false;
      return true;
    }
    void build(const Mesh& m) {
      mesh.set_vertices(m.vertices);
      mesh.set_triangles(m.triangles);
      indices.assign(mesh.t.begin(), mesh.t.end());
      array = std::make_unique<btTriangleIndexVertexArray>(int(m.triangles.size()), indices.data(), 3 * int(sizeof(int)),
                                                           int(m.vertices.size()), mesh.v.data(), 3 * int(sizeof(float)));
      shape = std::make_unique<btGImpactMeshShape>(array.get());
      shape->setMargin(0.0f);
      shape->updateBound();
      triangles = m.triangles.size(), vertices = m.vertices.size();
      set_range();
    }
    void set_range() {
      range_lo = Vec3::Constant(std::numeric_limits<double>::infinity());
      range_hi = -range_lo;
      for (std::size_t i = 0; i < mesh.v.size(); i += 3)
        for (int c = 0; c < 3; ++c) {
          range_lo[c] = std::min(range_lo[c], double(mesh.v[i + std::size_t(c)]));
          range_hi[c] = std::max(range_hi[c], double(mesh.v[i + std::size_t(c)]));
        }
      range_lo -= Vec3::Constant(1.0);
      range_hi += Vec3::Constant(1.0);
    }
  };
  struct Body {
    std::shared_ptr<Shape> own;          // deforming or static: world-space vertices
    std::shared_ptr<Shape> shared;       // rigid: the shape's, in shape coordinates
    std::shared_ptr<const Mesh> shape_of;
    btTransform transform = btTransform::getIdentity();
    bool identity = true;
    std::vector<std::uint32_t> rep;
    Shape& shape() { return shared ? *shared : *own; }
  };
  unsigned threads;
  TriangleTest test = TriangleTest::moller;
  std::unique_ptr<WorkerPool> pool;
  std::vector<Body> bodies;
  std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::shared_ptr<Shape>>> shapes;
  std::size_t builds = 0, refits = 0;

  static btTransform to_bt(const Eigen::Affine3d& p) {
    const Eigen::Matrix3d r = p.linear();
    btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)), btScalar(r(1, 0)), btScalar(r(1, 1)),
                      btScalar(r(1, 2)), btScalar(r(2, 0)), btScalar(r(2, 1)), btScalar(r(2, 2)));
    const Vec3 t = p.translation();
    return btTransform(basis, btVector3(btScalar(t.x()), btScalar(t.y()), btScalar(t.z())));
  }
  static bool isometry(const Eigen::Affine3d& pose) {
    const Eigen::Matrix3d r = pose.linear();
    return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12;
  }

  void sync(std::size_t i, const Object& o) {
    Body& b = bodies[i];
    if (o.rigid && o.rigid->shape && isometry(o.rigid->pose)) {  // built once per shape, moved
      auto& slot = shapes[o.rigid->shape.get()];
      if (slot.first != o.rigid->shape) {
        slot.first = o.rigid->shape;
        slot.second = std::make_shared<Shape>();
        slot.second->build(*o.rigid->shape);
        ++builds;
      }
      b.shared = slot.second, b.shape_of = o.rigid->shape, b.own.reset();
      b.identity = o.rigid->pose.matrix().isIdentity(0.0);
      b.transform = to_bt(o.rigid->pose);
    } else {  // world space: refitted when the vertices change
      b.shared.reset(), b.shape_of.reset();
      b.identity = true;
      b.transform = btTransform::getIdentity();
      if (!b.own || b.own->triangles != o.mesh.triangles.size() || b.own->vertices != o.mesh.vertices.size()) {
        b.own = std::make_shared<Shape>();
        b.own->build(o.mesh);
        ++builds;
      } else {
        b.own->mesh.set_vertices(o.mesh.vertices);  // in place: the array points at these floats
        if (b.own->within_range()) {  // refit
          b.own->shape->postUpdate();
          b.own->shape->updateBound();
          ++refits;
        } else {  // out of the quantization range: the set built again over the same arrays
          btGImpactMeshShapePart* part = b.own->shape->getMeshPart(0);
          part->lockChildShapes();
          const_cast<btGImpactBoxSet*>(part->getBoxSet())->buildSet();
          part->unlockChildShapes();
          b.own->shape->postUpdate();
          b.own->shape->updateBound();
          b.own->set_range();
          ++builds;
        }
      }
    }
    if (o.self && b.rep.size() != o.mesh.vertices.size()) vertex_representatives(o.mesh, SelfAdjacency::index, b.rep);
  }
};

BulletPeer::BulletPeer(unsigned threads, TriangleTest test) : impl_(std::make_unique<Impl>()) {
  impl_->threads = std::max(1u, threads);
  impl_->test = test;
  if (impl_->threads > 1) impl_->pool = std::make_unique<WorkerPool>(impl_->threads);
}
BulletPeer::~BulletPeer() = default;
std::size_t BulletPeer::builds() const { return impl_->builds; }
std::string BulletPeer::name() const { return std::string("Bullet 3 GImpact, refit") + (variant() ? ", scaled test" : ""); }
std::string BulletPeer::column() const { return variant() ? "Bullet sc" : "Bullet"; }
bool BulletPeer::variant() const { return impl_->test != TriangleTest::moller; }
std::string BulletPeer::setup() const {
  return "Bullet " + std::to_string(BT_BULLET_VERSION) +
         " GImpact: one btGImpactMeshShape per shape (quantized box set, margin 0), a rigid shape built once and moved "
         "by its transform, a deforming one refitted (built again beyond its quantization range); "
         "btGImpactQuantizedBvh::find_collision into a pair set kept per thread; test " + std::string(to_string(impl_->test)) +
         "; threads " + std::to_string(impl_->threads);
}
std::size_t BulletPeer::refits() const { return impl_->refits; }

PeerFrame BulletPeer::frame(const std::vector<Object>& objects) {
  Impl& m = *impl_;
  PeerFrame f;
  const auto t0 = Clock::now();
  m.bodies.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) m.sync(i, objects[i]);
  std::vector<Aabb> boxes(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    btVector3 lo, hi;
    m.bodies[i].shape().shape->getAabb(m.bodies[i].transform, lo, hi);
    boxes[i].lo = Vec3(lo.x(), lo.y(), lo.z());
    boxes[i].hi = Vec3(hi.x(), hi.y(), hi.z());
  }
  plan_object_pairs(boxes, objects, f);
  parallel_for(m.pool.get(), f.objects.size(), [&](std::size_t k) {
    const auto [a, b] = f.objects[k];
    Impl::Body& ba = m.bodies[a];
    Impl::Body& bb = m.bodies[b];
    const btGImpactBoxSet* sa = ba.shape().shape->getMeshPart(0)->getBoxSet();
    const btGImpactBoxSet* sb = bb.shape().shape->getMeshPart(0)->getBoxSet();
    thread_local btPairSet pairs;  // kept: its storage serves every pair and frame
    pairs.resize(0);
    btGImpactQuantizedBvh::find_collision(sa, ba.transform, sb, bb.transform, pairs);
    // The float test in A's frame: each candidate triangle of B moved by A^-1 B (as GImpact's own
    // algorithm moves each candidate triangle; nothing when both are in world space).
    Collector c;
    c.serial = true;  // filled by this lane alone (find_collision runs here)
    c.which = m.test;
    c.a = &ba.shape().mesh;
    c.b = &bb.shape().mesh;
    if (a != b && !(ba.identity && bb.identity)) {
      const btTransform rel = ba.transform.inverse() * bb.transform;
      c.move_b = true;
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) c.rel[4 * r + k] = rel.getBasis()[r][k];
        c.rel[4 * r + 3] = rel.getOrigin()[r];
      }
    }
    if (a == b) c.self_mesh = &objects[a].mesh, c.rep = &ba.rep;
    const btPairSet& found = pairs;  // this thread's
    c.test(
        [&found](std::size_t i) {
          return std::pair<std::uint32_t, std::uint32_t>(std::uint32_t(found[int(i)].m_index1),
                                                         std::uint32_t(found[int(i)].m_index2));
        },
        std::size_t(found.size()));
    f.per_pair[k] = c.take();
  });
  f.ms = ms_since(t0);
  sort_pairs(f);
  return f;
}

}  // namespace peelcd::bench
