// A plain Embree 3 user's setup, written from Embree's API documentation alone and sharing no
// setup code with EmbreePeer (bench/float_peers.cpp): it holds the bench's Embree rows against
// what a user would write (`peelcd bench --audit`; docs/performance.md, "The peers").
//
// Per object: its world vertices as floats, one user geometry (a primitive per triangle, the
// bounds callback's float box), a scene. An object whose vertices have not changed since it
// was built is a static scene with Embree's defaults; once they change, a dynamic scene of low
// quality whose geometry is refitted (RTC_BUILD_QUALITY_REFIT) at each commit. All in world space (no frame of
// one object for a rigid pair). Object pairs: every two scenes whose bounds overlap (all pairs
// compared); rtcCollide on each, Moller's test as published on the reported couples, the hits
// appended to the pair's list. An object asking for its self pairs (Object::self): its scene
// against itself, each couple once (rtcCollide reports both orders and a triangle with itself),
// couples sharing a vertex index left out (neighbours touch by construction), Moller's test.
#include "plain_setups.h"

#include "peelcd/bench/float_peers.h"
#include "peelcd/core/clock.h"
#include "peelcd/core/pairs.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <mutex>
#include <stdexcept>

namespace peelcd::bench {

namespace {

struct EmbreeSetup final : PlainPeer::Impl {
  struct Item {
    std::vector<float> v;
    std::vector<unsigned> t;
    RTCScene scene = nullptr;
    RTCGeometry geometry = nullptr;
    bool dynamic = false;
  };
  RTCDevice device = nullptr;
  std::vector<Item> items;

  // rtcCollide's callback context: the two items, the hits (under a lock: rtcCollide may call
  // back from several of TBB's threads once another device in the process asked for them).
  struct Hits {
    const Item* a;
    const Item* b;
    std::vector<std::uint64_t>* out;
    std::mutex mutex;
  };

  static void bounds(const RTCBoundsFunctionArguments* args) {
    const Item& it = *static_cast<const Item*>(args->geometryUserPtr);
    const unsigned* t = &it.t[3 * std::size_t(args->primID)];
    RTCBounds& o = *args->bounds_o;
    o.lower_x = o.lower_y = o.lower_z = INFINITY;
    o.upper_x = o.upper_y = o.upper_z = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const float* p = &it.v[3 * std::size_t(t[k])];
      o.lower_x = std::min(o.lower_x, p[0]), o.upper_x = std::max(o.upper_x, p[0]);
      o.lower_y = std::min(o.lower_y, p[1]), o.upper_y = std::max(o.upper_y, p[1]);
      o.lower_z = std::min(o.lower_z, p[2]), o.upper_z = std::max(o.upper_z, p[2]);
    }
  }

  static void corners(const Item& it, unsigned prim, std::array<float, 9>& c) {
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) c[std::size_t(3 * k + d)] = it.v[3 * std::size_t(it.t[3 * std::size_t(prim) + k]) + d];
  }

  static void collide(void* user, RTCCollision* c, unsigned n) {
    Hits& h = *static_cast<Hits*>(user);
    std::array<float, 9> ta, tb;
    std::lock_guard<std::mutex> lock(h.mutex);
    for (unsigned i = 0; i < n; ++i) {
      if (h.a == h.b && (c[i].primID0 >= c[i].primID1 || share_vertex(*h.a, c[i].primID0, c[i].primID1))) continue;
      corners(*h.a, c[i].primID0, ta);
      corners(*h.b, c[i].primID1, tb);
      if (tri_tri_moller(ta, tb)) h.out->push_back(pack_pair(c[i].primID0, c[i].primID1));
    }
  }

  static bool share_vertex(const Item& it, unsigned x, unsigned y) {
    const unsigned* p = &it.t[3 * std::size_t(x)];
    const unsigned* q = &it.t[3 * std::size_t(y)];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (p[i] == q[j]) return true;
    return false;
  }

  void build(Item& it, bool dynamic) {
    if (it.scene) rtcReleaseScene(it.scene);
    it.scene = rtcNewScene(device);
    if (dynamic) {
      // rtcSetGeometryBuildQuality(3): the per-geometry quality (REFIT) is used only under a
      // scene of low quality.
      rtcSetSceneFlags(it.scene, RTC_SCENE_FLAG_DYNAMIC);
      rtcSetSceneBuildQuality(it.scene, RTC_BUILD_QUALITY_LOW);
    }
    it.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(it.geometry, unsigned(it.t.size() / 3));
    rtcSetGeometryUserData(it.geometry, &it);
    rtcSetGeometryBoundsFunction(it.geometry, &EmbreeSetup::bounds, nullptr);
    if (dynamic) rtcSetGeometryBuildQuality(it.geometry, RTC_BUILD_QUALITY_REFIT);
    rtcCommitGeometry(it.geometry);
    rtcAttachGeometry(it.scene, it.geometry);
    rtcReleaseGeometry(it.geometry);
    rtcCommitScene(it.scene);
    it.dynamic = dynamic;
    ++builds;
  }

  // Object o's vertices into item i; built, refitted or left as it is.
  void sync(Item& it, const Object& o) {
    const std::size_t nv = 3 * o.mesh.vertices.size();
    bool changed = it.v.size() != nv;
    it.v.resize(nv);
    for (std::size_t i = 0; i < o.mesh.vertices.size(); ++i)
      for (int d = 0; d < 3; ++d) {
        const float x = float(o.mesh.vertices[i][d]);
        changed |= it.v[3 * i + std::size_t(d)] != x;
        it.v[3 * i + std::size_t(d)] = x;
      }
    const bool topology = !it.scene || it.t.size() != 3 * o.mesh.triangles.size();
    if (topology) {
      it.t.resize(3 * o.mesh.triangles.size());
      for (std::size_t i = 0; i < o.mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) it.t[3 * i + std::size_t(k)] = o.mesh.triangles[i][k];
      build(it, false);
    } else if (changed) {
      if (!it.dynamic) {
        build(it, true);
      } else {
        rtcCommitGeometry(it.geometry);
        rtcCommitScene(it.scene);
        ++refits;
      }
    }
  }

  EmbreeSetup() {
    device = rtcNewDevice("threads=1");
    if (!device) throw std::runtime_error("Embree: rtcNewDevice failed");
  }
  ~EmbreeSetup() override {
    for (Item& it : items)
      if (it.scene) rtcReleaseScene(it.scene);
    rtcReleaseDevice(device);
  }
  std::string setup() const override {
    return "Embree " + std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
           std::to_string(RTC_VERSION_PATCH) +
           " rtcCollide as written from its API documentation alone (bench/plain_embree.cpp): world-space float "
           "vertices, one user geometry per object, a static scene until the vertices change, then a dynamic scene "
           "of low quality, its geometry refitted at each commit; all object pairs' scene bounds compared; self pairs: "
           "the scene against itself, couples sharing a vertex index left out; test moller; threads 1";
  }
  PeerFrame frame(const std::vector<Object>& objects) override;
};

PeerFrame EmbreeSetup::frame(const std::vector<Object>& objects) {
  EmbreeSetup& m = *this;
  PeerFrame f;
  const auto t0 = Clock::now();
  if (m.items.size() != objects.size()) {
    for (Item& it : m.items)
      if (it.scene) rtcReleaseScene(it.scene);
    m.items = std::vector<Item>(objects.size());
  }
  for (std::size_t i = 0; i < objects.size(); ++i) m.sync(m.items[i], objects[i]);
  std::vector<RTCBounds> b(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) rtcGetSceneBounds(m.items[i].scene, &b[i]);
  for (std::size_t i = 0; i < objects.size(); ++i)
    for (std::size_t j = i + 1; j < objects.size(); ++j)
      if (b[i].lower_x <= b[j].upper_x && b[j].lower_x <= b[i].upper_x && b[i].lower_y <= b[j].upper_y &&
          b[j].lower_y <= b[i].upper_y && b[i].lower_z <= b[j].upper_z && b[j].lower_z <= b[i].upper_z) {
        f.objects.emplace_back(i, j);
        f.per_pair.emplace_back();
        Hits hits{&m.items[i], &m.items[j], &f.per_pair.back(), {}};
        rtcCollide(m.items[i].scene, m.items[j].scene, &EmbreeSetup::collide, &hits);
      }
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (objects[i].self && objects[i].mesh.triangles.size() >= 2) {
      f.objects.emplace_back(i, i);
      f.per_pair.emplace_back();
      Hits hits{&m.items[i], &m.items[i], &f.per_pair.back(), {}};
      rtcCollide(m.items[i].scene, m.items[i].scene, &EmbreeSetup::collide, &hits);
    }
  f.ms = ms_since(t0);
  // The table scores sorted lists: sorted after the clock stops (a user may not sort).
  for (std::vector<std::uint64_t>& p : f.per_pair) {
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    f.pairs += p.size();
  }
  return f;
}

}  // namespace

std::unique_ptr<PlainPeer::Impl> plain_embree() { return std::make_unique<EmbreeSetup>(); }

}  // namespace peelcd::bench
