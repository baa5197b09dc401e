#include "peelcd/bench/peers.h"

#include "peelcd/core/broad_phase.h"
#include "peelcd/core/reference.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>

namespace peelcd::bench {
namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
}  // namespace

PeerFrame cgal_frame(const std::vector<Object>& objects) {
  PeerFrame f;
  const auto t0 = Clock::now();
  std::vector<Aabb> boxes;
  boxes.reserve(objects.size());
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  f.objects = overlapping_pairs(boxes);
  for (const auto& [a, b] : f.objects) {
    f.per_pair.push_back(exact_colliding_pairs(objects[a].mesh, objects[b].mesh));
    f.pairs += f.per_pair.back().size();
  }
  f.ms = ms_since(t0);
  return f;
}

PeerFrame fcl_frame(const std::vector<Object>& objects) {
  using Model = fcl::BVHModel<fcl::AABBd>;
  PeerFrame f;
  const auto t0 = Clock::now();
  std::vector<Aabb> boxes;
  boxes.reserve(objects.size());
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  const auto pairs = overlapping_pairs(boxes);
  f.objects = pairs;
  // One BVH per object that takes part in a pair, built from scratch this frame.
  std::map<std::size_t, std::unique_ptr<Model>> built;
  const auto model = [&](std::size_t i) -> Model& {
    auto it = built.find(i);
    if (it != built.end()) return *it->second;
    auto m = std::make_unique<Model>();
    const Mesh& mesh = objects[i].mesh;
    std::vector<fcl::Vector3d> v(mesh.vertices.begin(), mesh.vertices.end());
    std::vector<fcl::Triangle> t;
    t.reserve(mesh.triangles.size());
    for (const Tri& tri : mesh.triangles) t.emplace_back(tri[0], tri[1], tri[2]);
    m->beginModel(int(t.size()), int(v.size()));
    m->addSubModel(v, t);
    m->endModel();
    return *built.emplace(i, std::move(m)).first->second;
  };
  for (const auto& [a, b] : pairs) {
    fcl::CollisionRequestd request(std::numeric_limits<std::size_t>::max() / 2, false);
    fcl::CollisionResultd result;
    // What fcl::collide() does for two AABB trees, minus its copy of both models (Debian's FCL
    // 0.7 frees that copy with a mismatched deallocator, which AddressSanitizer aborts on; the
    // copy is FCL's cost, so leaving it out only makes the peer faster). Identity transforms:
    // initialize() leaves the models as built.
    fcl::detail::MeshCollisionTraversalNode<fcl::AABBd> node;
    fcl::Transform3d tf_a = fcl::Transform3d::Identity(), tf_b = fcl::Transform3d::Identity();
    fcl::detail::initialize(node, model(a), tf_a, model(b), tf_b, request, result);
    fcl::detail::collide(&node);
    std::vector<std::uint64_t> found;
    found.reserve(result.numContacts());
    for (std::size_t k = 0; k < result.numContacts(); ++k) {
      const auto& c = result.getContact(k);
      found.push_back(std::uint64_t(std::uint32_t(c.b1)) << 32 | std::uint32_t(c.b2));
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    f.pairs += found.size();
    f.per_pair.push_back(std::move(found));
  }
  f.ms = ms_since(t0);
  return f;
}

}  // namespace peelcd::bench
