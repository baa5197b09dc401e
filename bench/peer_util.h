#pragma once
// What the peers of peelcd bench share (bench/peers.cpp, bench/float_peers.cpp): the object
// pairs a frame tests and a loop over them spread on a pool's lanes.
#include "peelcd/bench/peers.h"
#include "peelcd/core/aabb.h"
#include "peelcd/core/broad_phase.h"
#include "peelcd/core/worker_pool.h"

#include <algorithm>
#include <atomic>
#include <vector>

namespace peelcd::bench {

// Runs body(i) for i in [0, n) on `pool`'s lanes (or the calling thread without one).
template <class Body>
void parallel_for(WorkerPool* pool, std::size_t n, Body body) {
  if (!pool || n < 2) {
    for (std::size_t i = 0; i < n; ++i) body(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  auto lane = [&](unsigned) {
    for (std::size_t i; (i = next.fetch_add(1)) < n;) body(i);
  };
  pool->run(lane);
}

// f.objects: the object pairs whose `boxes` overlap, and (i, i) for every object asking for its
// self pairs (Object::self, two triangles or more), sorted; f.per_pair sized to them.
inline void plan_object_pairs(const std::vector<Aabb>& boxes, const std::vector<Object>& objects, PeerFrame& f) {
  f.objects = overlapping_pairs(boxes);
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (objects[i].self && objects[i].mesh.triangles.size() >= 2) f.objects.emplace_back(i, i);
  std::sort(f.objects.begin(), f.objects.end());
  f.per_pair.resize(f.objects.size());
}

}  // namespace peelcd::bench
