#pragma once
// The plain setups behind PlainPeer (include/peelcd/bench/plain_peers.h), one per file.
#include "peelcd/bench/plain_peers.h"

#include <algorithm>
#include <map>

namespace peelcd::bench {

std::unique_ptr<PlainPeer::Impl> plain_fcl();     // bench/plain_fcl.cpp
std::unique_ptr<PlainPeer::Impl> plain_embree();  // bench/plain_embree.cpp
std::unique_ptr<PlainPeer::Impl> plain_bullet();  // bench/plain_bullet.cpp

// An object the plain setups place by its pose: rigid with a shape and a pose of rotation and
// translation only (the libraries' transforms are isometries); the others in world space.
inline bool placed_rigid(const Object& o) {
  return o.rigid && o.rigid->shape &&
         (o.rigid->pose.linear().transpose() * o.rigid->pose.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <
             1e-12;
}

// A frame's hits gathered per object pair into f, each list sorted and distinct: the table scores
// sorted lists, and they are sorted after the clock stops (a user may not sort).
inline void take_hits(std::map<std::pair<std::size_t, std::size_t>, std::vector<std::uint64_t>>& hits, PeerFrame& f) {
  for (auto& [ab, p] : hits) {
    std::sort(p.begin(), p.end());
    p.erase(std::unique(p.begin(), p.end()), p.end());
    f.objects.push_back(ab);
    f.pairs += p.size();
    f.per_pair.push_back(std::move(p));
  }
}

}  // namespace peelcd::bench
