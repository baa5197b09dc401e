// The World's image route: the pairs the router (or Stage::image) sent to the image stage.
//   resident_image_pairs()  pairs of two bodies on a stage that batches its views: a rigid body
//                           drawn from its shape, resident on the stage, by its pose; a deforming
//                           one from its triangles, resident, and its vertices, uploaded once a
//                           frame (the GL stage selects the triangles in each view on the GPU);
//                           the views' PCS become the pair's candidates on the exact path's tasks.
//   image_pairs()           the others: the candidates' triangles copied into world-space
//                           objects for the Detector, which culls, plans and peels them.
#include "world_impl.h"
#include "peelcd/core/clock.h"
#include "peelcd/core/image/view.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace peelcd {
namespace {

// The world box of a node's shape-frame box under `pose`, grown by a relative 1e-9 of its
// magnitude: more than the rounding of the double arithmetic that carries it.
Aabb world_box(const FBox& f, const Eigen::Affine3d& pose) {
  const Vec3 lo(f.lo[0], f.lo[1], f.lo[2]), hi(f.hi[0], f.hi[1], f.hi[2]);
  const Vec3 c = pose * (0.5 * (lo + hi));
  const Vec3 e = pose.linear().cwiseAbs() * (0.5 * (hi - lo));
  const double slack = 1e-9 * (c.cwiseAbs() + e).maxCoeff() + 1e-300;
  Aabb out;
  out.lo = c - e - Vec3::Constant(slack);
  out.hi = c + e + Vec3::Constant(slack);
  return out;
}

// Where two bodies can meet inside `roi`: the node pairs of their trees (world boxes) whose
// boxes meet inside `roi`, refined level by level (each pair splits its larger node) until the
// nodes hold about kRegionLeaves leaves each (finer costs host work that the GPU's grid round,
// shaders/batch_select.comp, does better: on the 1,000-ball pile 8 leaves took 10 ms of host
// work a frame for 4,716 pairs, 32 leaves 2.5-5 ms), while a level holds at most kRegionPairs
// pairs, and not past two leaves; the
// region is the box of the last level's meetings. A point of both bodies in `roi` lies in a leaf
// box of each, and in each ancestor's box, so in a node pair of every level: the region holds
// it. Empty when no node pair meets (no contact possible). A side without a tree (null: a
// deforming body whose refit was put off) is one node, its world box `whole`, never split.
// `level` and `next` are scratch.
constexpr double kRegionLeaves = 32.0;
constexpr std::size_t kRegionPairs = 4096;
struct RegionSide {
  const Bvh* tree;  // null: `whole` alone
  Eigen::Affine3d pose;
  Aabb whole;
  bool leaf(std::uint32_t n) const { return !tree || tree->nodes()[n].leaf(); }
  Aabb box(std::uint32_t n) const { return tree ? world_box(tree->nodes()[n].box, pose) : whole; }
  double levels() const {
    return tree ? std::max(0.0, std::log2(double(tree->leaves()) / kRegionLeaves)) : 0.0;
  }
};
Aabb meeting_region(const RegionSide& sa, const RegionSide& sb, const Aabb& roi, std::vector<RegionEntry>& level,
                    std::vector<RegionEntry>& next) {
  Aabb out;
  if ((sa.tree && sa.tree->empty()) || (sb.tree && sb.tree->empty()) || roi.empty()) return out;
  level.clear();
  level.push_back({0u, 0u, sa.box(0), sb.box(0), Aabb{}});
  const int steps = int(std::ceil(sa.levels() + sb.levels()));
  for (int step = 0;; ++step) {
    // The level's pairs that still meet inside the ROI (their meeting boxes in place of theirs).
    std::size_t kept = 0, splittable = 0;
    for (const RegionEntry& e : level) {
      const Aabb meet = intersection(intersection(e.a, e.b), roi);
      if (meet.empty()) continue;
      level[kept] = e;
      level[kept].meet = meet;
      splittable += !(sa.leaf(e.i) && sb.leaf(e.j));
      ++kept;
    }
    level.resize(kept);
    if (splittable == 0 || step >= steps || kept + splittable > kRegionPairs) break;
    next.clear();
    for (const RegionEntry& e : level) {
      const bool xl = sa.leaf(e.i), yl = sb.leaf(e.j);
      if (xl && yl) {
        next.push_back(e);
        continue;
      }
      if (yl || (!xl && e.a.extent().maxCoeff() >= e.b.extent().maxCoeff())) {
        const BvhNode& x = sa.tree->nodes()[e.i];
        for (const std::uint32_t c : {e.i + 1, x.first}) next.push_back({c, e.j, sa.box(c), e.b, Aabb{}});
      } else {
        const BvhNode& y = sb.tree->nodes()[e.j];
        for (const std::uint32_t c : {e.j + 1, y.first}) next.push_back({e.i, c, e.a, sb.box(c), Aabb{}});
      }
    }
    level.swap(next);
  }
  for (const RegionEntry& e : level) {
    out.extend(e.meet.lo);
    out.extend(e.meet.hi);
  }
  return out;
}

}  // namespace

// A deforming body's tree is in world space (its pose the identity); one whose refit was put
// off this frame is its box (pair_boxes: the broad phase's).
Aabb World::Impl::contact_region(std::size_t p, const Aabb& roi, RegionScratch& scratch) const {
  const auto side = [&](std::size_t i) {
    const Body& b = bodies[ids[i]];
    return RegionSide{b.tree_current() ? &b.tree : nullptr, b.is_rigid ? b.pose : Eigen::Affine3d::Identity(), boxes[i]};
  };
  return meeting_region(side(pairs[p].first), side(pairs[p].second), roi, scratch.level, scratch.next);
}

// The median first-edge length of a body's triangles (as the Detector's culling measures its
// kept triangles): of a rigid body's shape computed once per shape, scaled by the pose's volume
// scale; of a deforming body over at most 1,025 of its triangles, evenly spread, each frame (its
// edges change; a sample keeps the cost per body, not per triangle).
double World::Impl::median_edge(const Body& b, std::vector<double>& edges) {
  const auto median = [&](const Mesh& m, std::size_t step) {
    edges.clear();  // (kept by the caller: no allocation per body and frame)
    for (std::size_t t = 0; t < m.triangles.size(); t += step) {
      const Tri& f = m.triangles[t];
      edges.push_back((m.vertices[f[1]] - m.vertices[f[0]]).norm());
    }
    if (edges.empty()) return 0.0;
    std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
    return edges[edges.size() / 2];
  };
  if (!b.is_rigid) return median(b.mesh, std::max<std::size_t>(1, b.mesh.triangles.size() / 1024));
  const Mesh* key = b.shape.get();
  auto it = shape_edges.find(key);
  if (it == shape_edges.end() || it->second.owner.expired())
    it = shape_edges.insert_or_assign(key, ShapeEdge{b.shape, median(*b.shape, 1)}).first;
  return it->second.edge * std::cbrt(std::fabs(b.pose.linear().determinant()));
}

// Whether the resident route serves this frame's image pairs (resident_pair()): the World
// batches its image pairs (batched_image()), conservative coverage, no margin.
bool World::Impl::resident_route(const DetectOptions& opt) const {
  return opt.conservative && opt.margin == 0.0 && batched_image();
}

// Two bodies (a self pair takes the copying route), each rigid or deforming.
bool World::Impl::resident_pair(std::size_t p) const {
  const Body& a = bodies[ids[pairs[p].first]];
  const Body& b = bodies[ids[pairs[p].second]];
  // An ill-conditioned pose keeps its body in world space, as the exact path does; a body whose
  // box leaves the float range the GPU draws in takes the copying route, whose Detector checks
  // (and refuses) the coordinates it would draw.
  const auto in_float = [](const Aabb& box) {
    return box.lo.allFinite() && box.hi.allFinite() && box.lo.cwiseAbs().maxCoeff() <= kFloatMax &&
           box.hi.cwiseAbs().maxCoeff() <= kFloatMax;
  };
  const auto drawable = [](const Body& x) { return x.is_rigid ? x.shape && !x.ill_conditioned : true; };
  return pairs[p].first != pairs[p].second && drawable(a) && drawable(b) && in_float(boxes[pairs[p].first]) &&
         in_float(boxes[pairs[p].second]);
}

// A deforming body whose refit may wait this frame: Stage::image on the resident route, the
// body's new vertices loaded by set_vertices() (their box known without the refit). Whether it
// does depends on its pairs (defer_refits()).
bool World::Impl::may_defer_refit(const Body& b, const DetectOptions& opt) const {
  return !b.is_rigid && b.refit_pending && b.points_loaded && opt.stage == Stage::image && resident_route(opt);
}

// After the broad phase: a body whose refit waits but that has a pair the resident route does
// not draw (a self pair, a pair with an ill-conditioned or out-of-range body: the copying
// route traverses it) is refitted now.
void World::Impl::defer_refits(unsigned lanes) {
  bool any = false;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (resident_pair(p)) continue;
    for (const std::size_t i : {pairs[p].first, pairs[p].second}) {
      Body& b = bodies[ids[i]];
      any |= b.refit_deferred;
      b.refit_deferred = false;
    }
  }
  if (any) refit_pending(lanes, false);
}

// With Stage::image, the resident route's pairs need no traversal: their candidates will be
// their PCS (untraversed; a view the stage cannot resolve traverses them after all).
void World::Impl::mark_untraversed(const DetectOptions& opt) {
  untraversed.clear();
  if (opt.stage != Stage::image || !resident_route(opt)) return;
  untraversed.assign(pairs.size(), 0);
  for (std::size_t p = 0; p < pairs.size(); ++p) untraversed[p] = resident_pair(p);
}

// The image-routed pairs of resident_pair(), where resident_route(): every view of every such
// pair in one call of the stage. A job's objects are the bodies' shapes and poses (rigid) or
// their world meshes as moving meshes (deforming), no corner copied, without triangle lists: the
// GL stage's batch selects each object's triangles in the view on the GPU from the resident shape
// or triangles (other paths select them on the host, job_triangles()); the triangles drawn are
// therefore not counted here (triangles_in_roi, triangles_drawn 0). Each pair's view is its
// region: its boxes' overlap narrowed by its trees' nodes (contact_region()); the pairs share the budget among
// themselves as the Detector's ROIs do. The PCS (unique IDs: the triangles;
// else expanded by the shapes' ID maps) replace the pair's candidates on its first task; the
// exact path's tests (test_candidates()) and contact gathering then serve them. A pair with a
// view the stage could not resolve is tested on its tree's candidates (traversed now if it was
// not): a superset of every couple the view could list.
void World::Impl::resident_image_pairs(const DetectOptions& opt, FrameResult& out) {
  peeled_resident.assign(pairs.size(), 0);
  resident_pairs.clear();
  for (Object& o : resident_objects) o.rigid.reset(), o.moving.reset();  // last frame's no longer held here
  if (!resident_route(opt)) return;
  for (std::size_t p = 0; p < pairs.size(); ++p)
    if (to_image[p] && resident_pair(p)) resident_pairs.push_back(p);
  if (resident_pairs.empty()) return;
  const auto t_views = Clock::now();

  // Each pair's region (its trees' nodes against its ROI, over the lanes); a pair whose bodies
  // cannot meet there is done: no contact.
  resident_regions.resize(resident_pairs.size());
  if (region_stacks.size() < frame_lanes) region_stacks.resize(frame_lanes);
  parallel("regions", resident_pairs.size(), frame_lanes, [&](std::size_t i, unsigned lane) {
    const std::size_t p = resident_pairs[i];
    resident_regions[i] = opt.cull == Cull::box ? out.pairs[p].roi  // the paper's: the whole ROI
                                                : contact_region(p, out.pairs[p].roi, region_stacks[lane]);
  });
  std::size_t kept = 0;
  for (std::size_t i = 0; i < resident_pairs.size(); ++i) {
    const std::size_t p = resident_pairs[i];
    PairResult& r = out.pairs[p];
    r.region = resident_regions[i];
    if (!r.region.empty()) {
      resident_pairs[kept] = p;
      resident_regions[kept++] = r.region;
      continue;
    }
    to_image[p] = 0;  // nothing to peel or test
    peeled_resident[p] = 1;
    r.exact_stage = false;
    r.candidates = 0;
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) tasks[k].candidates.clear();
  }
  resident_pairs.resize(kept);
  resident_regions.resize(kept);
  const std::size_t n = resident_pairs.size();
  if (n == 0) {
    out.timings.upload += ms_since(t_views);
    return;
  }

  // Tiles: as the Detector's (by need from the median edge, or equal shares, or forced).
  resident_tiles.assign(n, opt.resolution);
  if (opt.resolution == 0 && opt.cull == Cull::contact) {
    const double edge_texels = edge_texels_of(opt);
    // Each body's median edge, once a frame: a rigid body's from its shape's (kept in a map, here),
    // a deforming body's measured (over the lanes).
    frame_edges.assign(ids.size(), -1.0);
    edge_bodies.clear();
    for (const std::size_t p : resident_pairs)
      for (const std::size_t i : {pairs[p].first, pairs[p].second}) {
        if (frame_edges[i] >= 0.0) continue;
        const Body& b = bodies[ids[i]];
        if (b.is_rigid) {
          frame_edges[i] = median_edge(b, edge_scratch);
        } else {
          frame_edges[i] = 0.0;  // (listed once)
          edge_bodies.push_back(i);
        }
      }
    parallel("edges", edge_bodies.size(), frame_lanes, [&](std::size_t k, unsigned lane) {
      frame_edges[edge_bodies[k]] = median_edge(bodies[ids[edge_bodies[k]]], lane_scratch[lane]->edges);
    });
    resident_needs.clear();
    for (const std::size_t p : resident_pairs) {
      const double ea = frame_edges[pairs[p].first];
      const double eb = frame_edges[pairs[p].second];
      resident_needs.push_back(edge_tile_resolution(opt.budget, out.pairs[p].region, std::sqrt(ea * eb), edge_texels));
    }
    allocate_tiles(opt.budget, resident_needs, resident_tiles);
  } else if (opt.resolution == 0) {
    resident_tiles.assign(n, tile_resolution(opt.budget, n));
  }

  // The objects: shape and pose, or the deforming body's world mesh as a moving mesh.
  if (resident_objects.size() < 2 * n) resident_objects.resize(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t p = resident_pairs[i];
    for (int s = 0; s < 2; ++s) {
      Body& body = bodies[ids[s ? pairs[p].second : pairs[p].first]];
      Object& o = resident_objects[2 * i + s];
      if (o.name != body.name) o.name = body.name;
      if (body.is_rigid) {
        o.rigid = RigidMotion{body.shape, body.pose};
      } else {
        if (!body.topology) body.topology = std::make_shared<const char>(0);
        o.moving = MovingMesh{body.topology, &body.mesh};
      }
      o.self = false;
    }
  }

  // The views: one job per fused view frame (each pair's over the lanes).
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);
  resident_jobs.resize(n * frame_count);
  resident_job_first.resize(n + 1);
  for (std::size_t i = 0; i <= n; ++i) resident_job_first[i] = i * frame_count;
  parallel("jobs", n, frame_lanes, [&](std::size_t i, unsigned) {
    const std::size_t p = resident_pairs[i];
    PairResult& r = out.pairs[p];
    r.resolution = resident_tiles[i];
    for (std::size_t v = 0; v < frame_count; ++v) {
      PeelJob& job = resident_jobs[i * frame_count + v];  // (every field set: the entries are reused)
      job.view = make_padded_roi_view(r.region, boxes[pairs[p].first], boxes[pairs[p].second], frames[v], resident_tiles[i]);
      if (v == 0) r.epsilon = opt.epsilon > 0.0 ? opt.epsilon : job.view.texel();
      job.objects[0] = &resident_objects[2 * i];
      job.objects[1] = &resident_objects[2 * i + 1];
      job.triangles[0] = job.triangles[1] = nullptr;  // the stage selects them
      job.pair_index = p;
      job.view_index = int(v);
      job.ids = opt.ids;
      job.peel = opt.peel;
      job.epsilon = r.epsilon;
      job.slope = opt.slope;
      job.conservative = true;
      job.first = 1;  // (PeelJob's default)
      job.capture = false;
      job.grow = 0.0;
    }
  });
  FrameResult inner;  // the stage's work, added to the frame's at the end
  inner.timings.upload += ms_since(t_views);

  // Every view in one call of the stage.
  if (resident_peeled.size() < resident_jobs.size()) resident_peeled.resize(resident_jobs.size());
  {
    StageFrameScope scope;
    stage->counters = StageCounters{};
    scope.stage = stage.get();
    stage->begin_frame();
    stage->peel_batch(resident_jobs.data(), resident_jobs.size(), resident_peeled.data(), inner.timings);
    copy_stage_counters(stage->counters, inner);
  }

  // Per pair: its views' counters, then (over the lanes) its views' PCS united, sorted, unique,
  // as candidates; a pair with a view the stage could not resolve is traversed after, here.
  const auto t_pcs = Clock::now();
  resident_exhaustive.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    PairResult& r = out.pairs[resident_pairs[i]];
    for (std::size_t j = resident_job_first[i]; j < resident_job_first[i + 1]; ++j) {
      const PeelResult& one = resident_peeled[j];
      ++inner.rois_peeled;
      ++r.views_peeled;
      add_view_counters(one, inner);
      if (one.exhaustive) {
        ++inner.views_exhaustive;
        ++r.views_exhaustive;
        resident_exhaustive[i] = 1;
      }
      r.layers = std::max(r.layers, one.layers);
      r.passes += one.peel_passes;
    }
  }
  parallel("pcs", n, frame_lanes, [&](std::size_t i, unsigned lane) {
    const std::size_t p = resident_pairs[i];
    PairResult& r = out.pairs[p];
    const Body& a = bodies[ids[pairs[p].first]];
    const Body& b = bodies[ids[pairs[p].second]];
    LaneScratch& ls = *lane_scratch[lane];
    std::vector<std::uint64_t>& keys = ls.pcs_keys;
    keys.clear();
    for (std::size_t j = resident_job_first[i]; j < resident_job_first[i + 1]; ++j)
      for (const IdPair& c : resident_peeled[j].pcs) keys.push_back(pack_pair(c.a, c.b));
    sort_unique_pairs(keys, ls.sorted);
    r.pcs_count = keys.size();
    r.exact_stage = false;
    to_image[p] = 0;
    peeled_resident[p] = 1;
    if (resident_exhaustive[i]) return;  // (below)
    if (first_task[p] == first_task[p + 1]) {  // no node pair of its trees overlaps: no contact
      r.candidates = 0;
      return;
    }
    for (std::size_t k = first_task[p] + 1; k < first_task[p + 1]; ++k) tasks[k].candidates.clear();
    std::vector<std::uint64_t>& candidates = tasks[first_task[p]].candidates;
    if (opt.ids == IdMode::unique) {  // an ID is its triangle
      for (const std::uint64_t k : keys)
        if (pair_a(k) >= a.local().triangles.size() || pair_b(k) >= b.local().triangles.size())
          throw std::out_of_range("peelcd::World: triangle ID out of range");
      candidates.assign(keys.begin(), keys.end());
    } else {
      ls.pcs.clear();
      for (const std::uint64_t k : keys) ls.pcs.push_back(IdPair{pair_a(k), pair_b(k)});
      ls.map_a.rebuild(a.local(), opt.ids);
      ls.map_b.rebuild(b.local(), opt.ids);
      candidates.clear();
      expand_pcs(ls.pcs, ls.map_a, ls.map_b, candidates, ls.sorted);
    }
    r.candidates = candidates.size();
    // A pair with several tasks (a large one, planned for the lanes): its candidates in as many
    // contiguous runs, one a task, for the exact tests over the lanes.
    const std::size_t m = first_task[p + 1] - first_task[p];
    if (m > 1) {
      const std::size_t total = candidates.size();
      for (std::size_t c = 1; c < m; ++c)
        tasks[first_task[p] + c].candidates.assign(candidates.begin() + std::ptrdiff_t(total * c / m),
                                                   candidates.begin() + std::ptrdiff_t(total * (c + 1) / m));
      candidates.resize(total / m);
    }
  });
  for (std::size_t i = 0; i < n; ++i) {  // the tree's candidates for a view not resolved
    const std::size_t p = resident_pairs[i];
    if (!resident_exhaustive[i] || untraversed.empty() || !untraversed[p]) continue;
    for (const std::size_t b : {pairs[p].first, pairs[p].second}) {
      refit_now(bodies[ids[b]]);  // (a refit put off: its single task starts at the roots)
      bodies[ids[b]].ensure_world_tree();  // (a copy drawn only had none made: copy_paired())
    }
    // Tasks that are the lanes' shares of its PCS (all from the roots: plan_tasks()) traverse
    // once, the others each from its node pair.
    const std::size_t first = first_task[p], last = first_task[p + 1];
    const bool shares = last - first > 1 && tasks[first + 1].start == BvhNodePair{0u, 0u};
    std::size_t count = 0;
    for (std::size_t k = first; k < last; ++k) {
      if (shares && k > first) {
        tasks[k].candidates.clear();
        continue;
      }
      traverse_task(k, 0);
      count += tasks[k].candidates.size();
    }
    out.pairs[p].candidates = count;
  }
  inner.timings.cpu += ms_since(t_pcs);
  out.add_image_work(inner);
}

// The image stage on every pair routed there, in one frame of the Detector (one batch of views
// for all of them): per pair, the candidates' triangles of each body, in world space, as two
// objects (triangle k of each is the k-th of its ascending list), the Detector asked for those
// pairs alone (Detector::only_pairs()); the contacts mapped back to the bodies' triangles.
void World::Impl::image_pairs(const DetectOptions& opt, FrameResult& out, std::size_t only) {
  const auto t_copy = Clock::now();  // the candidates' triangles copied: part of `upload`
  // The objects and triangle lists are kept from frame to frame, their storage reused (`used`:
  // how many this frame fills).
  std::size_t used = 0;
  image_of.clear();
  image_only.clear();
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!to_image[p] || (only != kAllPairs && p != only)) continue;
    const Body* body[2] = {&bodies[ids[pairs[p].first]], &bodies[ids[pairs[p].second]]};
    const std::size_t first = used;
    used += 2;
    if (image_objects.size() < used) image_objects.resize(used), image_kept.resize(used);
    std::vector<std::uint32_t>* kept[2] = {&image_kept[first], &image_kept[first + 1]};
    kept[0]->clear();
    kept[1]->clear();
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k)
      for (const std::uint64_t c : tasks[k].candidates) {
        kept[0]->push_back(pair_a(c));
        kept[1]->push_back(pair_b(c));
      }
    for (int s = 0; s < 2; ++s) {
      std::vector<std::uint32_t>& ks = *kept[s];
      std::sort(ks.begin(), ks.end());
      ks.erase(std::unique(ks.begin(), ks.end()), ks.end());
      Object& o = image_objects[first + s];
      o.mesh.vertices.resize(3 * ks.size());
      o.mesh.triangles.resize(ks.size());
      const Mesh& local = body[s]->local();
      for (std::size_t i = 0; i < ks.size(); ++i) {
        const Tri& t = local.triangles[ks[i]];
        const std::uint32_t base = std::uint32_t(3 * i);
        for (int c = 0; c < 3; ++c) o.mesh.vertices[base + c] = body[s]->world(t[c]);
        o.mesh.triangles[i] = Tri{base, base + 1, base + 2};
      }
      o.name = body[s]->name;
      o.rigid.reset();
      o.self = false;
    }
    image_only.emplace_back(first, first + 1);
    image_of.push_back(p);
  }
  image_objects.resize(used);  // (objects beyond this frame's count: not the Detector's)
  image_kept.resize(used);
  out.timings.upload += ms_since(t_copy);
  if (image_of.empty()) return;
  if (!detector) detector = std::make_unique<Detector>(stage);
  DetectOptions image = opt;
  image.stage = Stage::image;
  FrameResult inner;
  struct Only {  // the Detector back to every pair, also on an exception
    Detector& d;
    ~Only() { d.only_pairs(nullptr); }
  } reset_pairs{*detector};
  detector->only_pairs(&image_only);
  detector->detect(image_objects, image, inner);
  for (const PairResult& ir : inner.pairs) {
    const std::size_t i = ir.object_a / 2;
    const std::vector<std::uint32_t>& ka = image_kept[2 * i];
    const std::vector<std::uint32_t>& kb = image_kept[2 * i + 1];
    PairResult& r = out.pairs[image_of[i]];
    const double pe = r.predicted_exact_ms, pi = r.predicted_image_ms;
    const std::size_t oa = r.object_a, ob = r.object_b;
    const Aabb roi = r.roi;
    r = ir;
    r.object_a = oa;
    r.object_b = ob;
    r.roi = roi;
    r.predicted_exact_ms = pe;
    r.predicted_image_ms = pi;
    r.triangles_in_roi_a = ka.size();
    r.triangles_in_roi_b = kb.size();
    r.pcs.clear();  // IDs of the peeled copies, not of the bodies: the count (pcs_count) stays
    for (Contact& c : r.colliding) {
      c.tri_a = ka[c.tri_a];
      c.tri_b = kb[c.tri_b];
    }
    sort_contacts(r.colliding);
  }
  out.add_image_work(inner);
}

}  // namespace peelcd
