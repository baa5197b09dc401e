#pragma once
// What a user would pick instead of peelcd, run on the same frames (peelcd bench), each given
// the same input and the optimisations a user of that library would apply:
//   cgal: per object pair whose boxes overlap, only the triangles whose boxes touch the overlap
//         box (the crop peelcd's ROI makes too), CGAL box_intersection_d over their boxes, then
//         the exact triangle test (core/exact/narrow_phase.h). No preprocessing; also the reference.
//   fcl:  FCL 0.7 (FclPeer), object pairs from FCL's own broad phase
//         (DynamicAABBTreeCollisionManager), then every colliding triangle pair:
//         - two rigid objects: OBBRSS trees built once from their shapes and moved by their poses
//           (FCL's oriented traversal: no refit, no copy);
//         - a static object (rigid at the identity pose): its AABB tree built once, kept;
//         - two deforming objects, Deforming::refit: AABB trees of the world meshes, refitted
//           through FCL's update API every frame (rebuilt when the topology changes);
//         - otherwise (Deforming::rebuild, or a moving rigid object against another kind): AABB
//           trees of only the triangles touching the pair's overlap box, built for the pair.
//         The benchmark runs both modes and compares with the faster.
// Both spread the object pairs' narrow phases over `threads` threads (1 = the calling thread).
#include "peelcd/core/mesh.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace peelcd::bench {

struct PeerFrame {
  double ms = 0;
  std::size_t pairs = 0;  // colliding triangle pairs reported (all object pairs summed)
  std::vector<std::pair<std::size_t, std::size_t>> objects;  // the object pairs tested (a < b; a == b: an
                                                             // object's self pairs, Object::self)
  // Per entry of `objects`: the reported triangle pairs, packed as core/image/id_map.h pair keys
  // (tri_a << 32 | tri_b), sorted, distinct.
  std::vector<std::vector<std::uint64_t>> per_pair;
};

PeerFrame cgal_frame(const std::vector<Object>& objects, unsigned threads = 1);

// A peer of `peelcd bench`: one library set up one way, a row of the table. A new peer is a class
// implementing this and one line in make_peers() (bench/suite.cpp).
class Peer {
 public:
  virtual ~Peer() = default;
  virtual std::string name() const = 0;    // the row: "Embree 3 rtcCollide, refit"
  virtual std::string column() const = 0;  // its short name in the per-phase table
  virtual std::string library() const = 0; // "FCL", "Embree", "Bullet": "x FCL" takes the faster FCL row
  // A labelled variant of a peer (another test than its users'): printed, never the "best" peer.
  virtual bool variant() const { return false; }
  // One frame of all colliding triangle pairs; state may be kept from frame to frame.
  virtual PeerFrame frame(const std::vector<Object>& objects) = 0;
  virtual std::string setup() const = 0;   // its settings, in words (bench prints them)
  virtual std::size_t builds() const = 0;  // trees or scenes built so far
  virtual std::size_t refits() const = 0;  // refits so far
};

class FclPeer : public Peer {
 public:
  enum class Deforming { refit, rebuild };
  FclPeer(Deforming deforming, unsigned threads = 1);
  ~FclPeer() override;
  FclPeer(const FclPeer&) = delete;
  FclPeer& operator=(const FclPeer&) = delete;

  std::string name() const override;
  std::string column() const override;
  std::string library() const override { return "FCL"; }
  std::string setup() const override;
  // One frame. State kept from frame to frame: the trees (rigid shapes' once, deforming
  // objects' refitted when their topology is unchanged) and the broad-phase manager.
  PeerFrame frame(const std::vector<Object>& objects) override;

  // Trees built and kept (one per rigid shape, per static or refitted object), refits, and
  // cropped trees built for one pair and frame, so far.
  std::size_t builds() const override;
  std::size_t refits() const override;
  std::size_t pair_builds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::bench
