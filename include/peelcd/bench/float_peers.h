#pragma once
// The peers a user wanting "all colliding triangle pairs" on a CPU would pick besides FCL and
// CGAL (peelcd bench): Intel Embree 3's rtcCollide and Bullet 3's GImpact box sets, each with
// Moller's float triangle test as published (tri_tri_moller(); tri_tri_float() a labelled
// variant), set up as their own documentation and examples do (setup() says it in words):
//   EmbreePeer: one scene per object holding one user geometry (a primitive per triangle, its
//     float box the bounds callback's), rtcCollide between the scenes of every object pair whose
//     boxes overlap (the boxes: the scenes' own bounds); a self pair: rtcCollide of the scene with
//     itself (each couple tested once: it reports both orders). An object nothing moves is a
//     static scene (Embree's defaults); what moves is a dynamic scene of low quality, its
//     geometry refitted (RTC_BUILD_QUALITY_REFIT) or rebuilt (LOW: Morton) by the `Update` mode;
//     a rigid object is static until it first moves. A scene of two rigid objects keeps A's
//     tree in A's frame, built once, and maps B's vertices into A's frame every frame
//     (rtcCollide takes no transform).
//   BulletPeer: one btGImpactMeshShape per shape (its quantized box set, margin 0), built once
//     for a rigid shape and moved by the object's transform (GImpact's own find_collision takes
//     both transforms), refitted (postUpdate(), updateBound()) for a deforming object and built
//     again when its vertices leave the quantization range fixed at its build (a refit clamps to
//     it); object pairs from the shapes' transformed boxes, then
//     btGImpactQuantizedBvh::find_collision into a pair set each thread keeps.
// Both use one thread per object pair, the pairs spread over `threads` threads; neither
// allocates per callback once its buffers have grown.
#include "peelcd/bench/peers.h"

#include <array>
#include <memory>
#include <string>

namespace peelcd::bench {

// Moller's interval test ("A Fast Triangle-Triangle Intersection Test", 1997), in float, as the
// peers' examples use it: in a frame at t's first corner scaled to the pair's extent (his
// no-division form multiplies up to five small differences, which underflow for small
// triangles), its plane-distance snap at the input's float rounding (not his absolute 1e-6):
// true when the triangles meet.
bool tri_tri_float(const std::array<float, 9>& t, const std::array<float, 9>& u);
// Moller's test as published (tritri.c's NoDivTriTriIsect, its USE_EPSILON_TEST switch off), in
// float on the coordinates as given: the test Embree's and Bullet's users reach for, and the
// peers' default. Its products underflow for small triangles and its signs round: its misses
// and false pairs are the peers' rows'.
bool tri_tri_moller(const std::array<float, 9>& t, const std::array<float, 9>& u);

// Which float test a peer runs on its candidate couples: Moller's as published (the default),
// or tri_tri_float() (a labelled variant).
enum class TriangleTest { moller, scaled };
const char* to_string(TriangleTest test);

class EmbreePeer : public Peer {
 public:
  enum class Update { refit, rebuild_low };
  EmbreePeer(Update update, unsigned threads = 1, TriangleTest test = TriangleTest::moller);
  ~EmbreePeer() override;
  EmbreePeer(const EmbreePeer&) = delete;
  EmbreePeer& operator=(const EmbreePeer&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "Embree"; }
  bool variant() const override;  // the scaled test
  PeerFrame frame(const std::vector<Object>& objects) override;
  std::size_t builds() const override;  // scenes committed for the first time or rebuilt
  std::size_t refits() const override;  // commits of moved or deformed trees
  std::string setup() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class BulletPeer : public Peer {
 public:
  explicit BulletPeer(unsigned threads = 1, TriangleTest test = TriangleTest::moller);
  ~BulletPeer() override;
  BulletPeer(const BulletPeer&) = delete;
  BulletPeer& operator=(const BulletPeer&) = delete;
  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "Bullet"; }
  bool variant() const override;  // the scaled test
  PeerFrame frame(const std::vector<Object>& objects) override;
  std::size_t builds() const override;
  std::size_t refits() const override;
  std::string setup() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::bench
