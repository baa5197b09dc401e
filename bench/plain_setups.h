#pragma once
// The plain setups behind PlainPeer (include/peelcd/bench/plain_peers.h), one per file.
#include "peelcd/bench/plain_peers.h"

namespace peelcd::bench {

std::unique_ptr<PlainPeer::Impl> plain_fcl();     // bench/plain_fcl.cpp
std::unique_ptr<PlainPeer::Impl> plain_embree();  // bench/plain_embree.cpp
std::unique_ptr<PlainPeer::Impl> plain_bullet();  // bench/plain_bullet.cpp

}  // namespace peelcd::bench
