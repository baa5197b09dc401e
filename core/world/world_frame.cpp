// A frame of the World (World::collide()): the pending refits, the broad phase over the bodies'
// boxes, the traversals (one task per pair, or its first node pairs over the lanes), the router,
// the exact tests or the image stage, the relations.
#include "world_impl.h"
#include "../exact/bvh_traverse.h"
#include "peelcd/core/exact/relation.h"
#include "peelcd/core/clock.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/narrow_phase.h"

#include <algorithm>
#include <stdexcept>

namespace peelcd {
void World::Impl::refit_pending(unsigned lanes, bool all) {
  refit_chunks.clear();
  refit_bodies.clear();
  refit_parts.clear();
  for (Body& b : bodies) {
    if (!b.alive || !b.refit_pending || (!all && b.refit_deferred)) continue;
    b.refit_deferred = false;
    const bool large = b.mesh.triangles.size() >= kSplitRefitTriangles;
    const std::size_t chunks = lanes > 1 && large ? lanes : 1;
    const std::size_t nv = b.mesh.vertices.size(), nl = b.tree.leaves();
    refit_bodies.push_back({&b, refit_chunks.size(), refit_chunks.size() + chunks, false});
    for (std::size_t k = 0; k < chunks; ++k) {
      if (b.points_loaded && b.points_rounded)  // rounded by set_vertices(): no vertex range
        refit_chunks.push_back({refit_bodies.size() - 1, 0, 0, nl * k / chunks, nl * (k + 1) / chunks,
                                k == 0 ? b.loaded_box : Aabb{}});
      else
        refit_chunks.push_back(
            {refit_bodies.size() - 1, nv * k / chunks, nv * (k + 1) / chunks, nl * k / chunks, nl * (k + 1) / chunks, Aabb{}});
    }
    const std::size_t parts = b.tree.plan_parts(large ? kRefitParts : 1);  // (whatever the lanes)
    for (std::size_t k = parts; k-- > 0;) refit_parts.push_back({refit_bodies.size() - 1, k});  // (back to front, as refit_nodes)
  }
  if (refit_bodies.empty()) return;
  if (std::any_of(refit_chunks.begin(), refit_chunks.end(), [](const RefitChunk& c) { return c.vertex_begin < c.vertex_end; }))
    parallel("refit vertices", refit_chunks.size(), lanes, [&](std::size_t k, unsigned) {  // the vertices rounded (unless loaded)
      RefitChunk& c = refit_chunks[k];
      Body& b = *refit_bodies[c.body].body;
      if (c.vertex_begin < c.vertex_end) c.exact = b.tree.refit_vertices(b.mesh.vertices, c.vertex_begin, c.vertex_end);
    });
  parallel("refit leaves", refit_chunks.size(), lanes, [&](std::size_t k, unsigned) {  // the leaves from them
    const RefitChunk& c = refit_chunks[k];
    Body& b = *refit_bodies[c.body].body;
    b.tree.refit_leaves(b.mesh.vertices, c.leaf_begin, c.leaf_end);
  });
  // The nodes, a large tree's in subtrees (the nodes last: the traversal that follows reads
  // them; refitted with their leaves, subtree by subtree, a frame of the waving 1.3M-triangle
  // spheres took 0.3 ms more on one thread).
  parallel("refit nodes", refit_parts.size(), lanes, [&](std::size_t k, unsigned) {
    refit_bodies[refit_parts[k].body].body->tree.refit_part(refit_parts[k].part);
  });
  refit_grown.clear();
  for (std::size_t k = 0; k < refit_bodies.size(); ++k) {  // the nodes above the subtrees
    RefitBody& r = refit_bodies[k];
    Aabb exact;
    for (std::size_t c = r.first; c < r.last; ++c)
      exact.lo = exact.lo.cwiseMin(refit_chunks[c].exact.lo), exact.hi = exact.hi.cwiseMax(refit_chunks[c].exact.hi);
    r.body->tree.refit_top(exact);
    r.body->refit_pending = r.body->points_loaded = false;
    if (r.body->tree.grown()) refit_grown.push_back(k);
  }
  if (!refit_grown.empty()) rebuild_grown(lanes);
  stats.full_refits += refit_bodies.size();
  for (const RefitBody& r : refit_bodies) stats.builds += r.rebuilt;
}

// The trees refits grew past the limit, built again: a large tree's subtrees over the lanes (the
// same tree as one build: Bvh::plan_build()). Its top splits and its boxes' and corners' passes
// stay one lane's: a 100k-triangle build takes about 0.3x its one-lane time in 8 parts.
void World::Impl::rebuild_grown(unsigned lanes) {
  parallel("rebuild plan", refit_grown.size(), lanes, [&](std::size_t k, unsigned) {
    RefitBody& r = refit_bodies[refit_grown[k]];
    const bool large = r.body->mesh.triangles.size() >= kSplitRefitTriangles;
    r.parts = r.body->tree.plan_build(r.body->mesh.vertices, r.body->mesh.triangles, lanes > 1 && large ? lanes : 1);
    r.rebuilt = true;
  });
  build_parts.clear();
  for (const std::size_t k : refit_grown)
    for (std::size_t j = 0; j < refit_bodies[k].parts; ++j) build_parts.push_back({k, j});
  parallel("rebuild", build_parts.size(), lanes, [&](std::size_t k, unsigned) {
    refit_bodies[build_parts[k].body].body->tree.build_part(build_parts[k].part);
  });
  parallel("rebuild finish", refit_grown.size(), lanes, [&](std::size_t k, unsigned) {
    Body& b = *refit_bodies[refit_grown[k]].body;
    b.tree.finish_build(b.mesh.triangles);
  });
}

void World::Impl::self_pair(Body& a, std::size_t first, std::size_t last, PairResult& r, ContactSortScratch& scratch) {
  if (!(a.is_rigid && a.self_cached)) {
    a.self_contacts.clear();
    std::size_t n = 0;
    for (std::size_t k = first; k < last; ++k) {
      a.self_contacts.insert(a.self_contacts.end(), tasks[k].contacts.begin(), tasks[k].contacts.end());
      n += tasks[k].tested;
    }
    sort_contacts(a.self_contacts, scratch);
    a.self_cached = a.is_rigid;
    a.self_detail = detail;
    r.candidates = n;
  } else {
    r.candidates = 0;  // nothing tested this frame
  }
  r.colliding = a.self_contacts;
  if (a.is_rigid)
    for (Contact& c : r.colliding)
      if (c.classified()) {
        c.p = a.pose * c.p;
        c.q = a.pose * c.q;
      }
}

// Stage::automatic where the image route is the resident one (conservative, no margin, batched)
// and the stage's work runs on a GPU, unless World::time_routes() said otherwise.
bool World::Impl::timing_routes(const DetectOptions& opt) const {
  if (opt.stage != Stage::automatic || !resident_route(opt)) return false;
  return time_routes_opt ? *time_routes_opt : !stage->runs_on_cpu();
}

void World::Impl::collide(const DetectOptions& opt, FrameResult& out) {
  routes_timed = timing_routes(opt);
  if (!*routes_timed) {
    stats.route_comparing = false;
    collide_frame(opt, out);
    return;
  }
  const bool image = route_timer.next() == RouteTimer::image;
  stats.route_comparing = route_timer.comparing();
  if (image) {
    image_opt = opt;  // assigned: the strings' storage kept from frame to frame
    image_opt.stage = Stage::image;
    collide_frame(image_opt, out);
    ++stats.image_route_frames;
  } else {
    collide_frame(opt, out);
  }
  route_timer.record(out.timings.total, pairs.size());
}

void World::Impl::collide_frame(const DetectOptions& opt, FrameResult& out) {
  validate_options(opt, stage->max_resolution());
  const auto t_total = Clock::now();
  out.reset_counters();
  stats.node_pairs = stats.candidates = stats.vertices_transformed = 0;
  loops_ms = 0.0;
  model_start();
  model_first = model_loops.size();
  const unsigned lanes = lanes_for(opt);
  frame_lanes = lanes;
  detail = opt.contacts;
  for (Body& b : bodies) b.refit_deferred = b.alive && may_defer_refit(b, opt);
  refit_pending(lanes, false);

  auto t0 = Clock::now();
  find_pairs(opt, lanes);
  defer_refits(lanes);
  const std::size_t used = plan_tasks(lanes);
  keep_wide_views();
  mark_untraversed(opt);
  traverse(used, lanes);
  out.timings.aabb = ms_since(t0);

  route_pairs(opt, used, out);
  keep_split_costs(used);  // (the tasks' costs, for the next frame's splits; first_task set)
  resident_image_pairs(opt, out);  // its pairs' candidates: their PCS, tested below
  t0 = Clock::now();
  test_candidates(opt, used, lanes);
  gather_contacts(out);
  out.timings.cpu = ms_since(t0);

  if (batched_image()) {
    image_pairs(opt, out);
  } else {
    for (std::size_t p = 0; p < pairs.size(); ++p)
      if (to_image[p]) image_pairs(opt, out, p);
  }
  t0 = Clock::now();
  relate(opt, out);
  out.timings.cpu += ms_since(t0);
  out.renderer = stage->renderer();
  out.timings.total = ms_since(t_total);
  stats.loops_ms = loops_ms;
  stats.one_lane_ms = std::max(0.0, out.timings.total - loops_ms);
  stats.model_ms = 0.0;
  if (model_lanes) {
    stats.model_ms = stats.one_lane_ms;
    for (std::size_t k = model_first; k < model_loops.size(); ++k) stats.model_ms += model_loops[k].span_ms;
  }
  model_done = true;
}

// The lane model's replay of one loop (model_items: its items' times on this thread): `lanes`
// lanes start on contiguous ranges of the items, front to back; a lane done with its range
// takes the others' last items, back to front, trying the next lanes in turn (as
// WorkerPool::for_each). The lane that is free first takes the next item. The span is the
// time the last lane finishes.
void World::Impl::model_loop(const char* step, unsigned lanes) {
  const std::size_t n = model_items.size();
  LaneLoop loop;
  loop.step = step;
  loop.items = n;
  for (const double t : model_items) loop.total_ms += t, loop.longest_ms = std::max(loop.longest_ms, t);
  struct Lane {
    std::size_t front, back;
    double t = 0.0;
    bool done = false;
  };
  Lane ls[kMaxModelLanes];
  lanes = std::min(lanes, kMaxModelLanes);
  for (unsigned l = 0; l < lanes; ++l) ls[l] = Lane{n * l / lanes, n * (l + 1) / lanes};
  for (;;) {
    unsigned l = lanes;
    for (unsigned k = 0; k < lanes; ++k)
      if (!ls[k].done && (l == lanes || ls[k].t < ls[l].t)) l = k;
    if (l == lanes) break;
    Lane& me = ls[l];
    if (me.front < me.back) {
      me.t += model_items[me.front++];
      continue;
    }
    me.done = true;
    for (unsigned k = 1; k < lanes; ++k) {
      Lane& victim = ls[(l + k) % lanes];
      if (victim.front < victim.back) {
        me.t += model_items[--victim.back];
        me.done = false;
        break;
      }
    }
  }
  for (unsigned l = 0; l < lanes; ++l) loop.span_ms = std::max(loop.span_ms, ls[l].t);
  model_loops.push_back(loop);
}

// The broad phase: each body's box (its tree's root, moved by its pose; small rigid bodies
// copied into world space first), the overlapping pairs (indices into ids, a < b), and the self
// pairs (i, i) of the bodies asking for self-collision (set_self, DetectOptions::self).
void World::Impl::find_pairs(const DetectOptions& opt, unsigned lanes) {
  boxes.clear();
  ids.clear();
  for (BodyId id = 0; id < bodies.size(); ++id) {
    if (!bodies[id].alive) continue;
    bodies[id].enter_frame();
    if (bodies[id].self_detail != opt.contacts) bodies[id].self_cached = false;  // cached with other detail
    ids.push_back(id);
    boxes.push_back(bodies[id].world_box());
    const Aabb& w = boxes.back();
    if (opt.stage != Stage::exact && !w.empty() &&
        std::max(w.lo.cwiseAbs().maxCoeff(), w.hi.cwiseAbs().maxCoeff()) > kFloatMax)
      throw std::invalid_argument("peelcd::World: " + label_of(bodies[id].name, id) +
                                  " reaches outside the float range (|x| <= 3.4e38) the image stage works in");
    boxes.back() = w.grown(0.5 * opt.margin);  // proximity: boxes within the margin of each other make a pair
  }
  overlapping_pairs(boxes, pairs, sweep);
  copy_paired(opt, lanes);
  bool any_self = false;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    Body& b = bodies[ids[i]];
    if (!(opt.self || b.self) || b.local().triangles.size() < 2) continue;
    b.representatives(opt.self_adjacency);
    pairs.emplace_back(i, i);
    any_self = true;
  }
  if (any_self) std::sort(pairs.begin(), pairs.end());
}

// pairs_of: each body's pairs with other bodies.
void World::Impl::count_pairs() {
  pairs_of.assign(ids.size(), 0);
  for (const auto& [i, j] : pairs)
    if (i != j) ++pairs_of[i], ++pairs_of[j];
}

// The small rigid bodies the broad phase paired whose copies are stale: copied into world
// space when still (the copy serves the next frames too) or in kCopyPairs pairs or more (the
// copy and its tree serve them all; the pairs whose exact boxes then do not overlap are
// dropped), else traversed through their pose this frame (never an ill-conditioned pose:
// kPosedConditionLimit). pairs_of: each body's pairs.
void World::Impl::copy_paired(const DetectOptions& opt, unsigned lanes) {
  count_pairs();
  // With Stage::image on the resident route, a body all of whose pairs that route draws (from
  // its shape, by its pose) needs no world tree: no traversal reads it (a pair whose views the
  // stage could not resolve makes it then: resident_image_pairs()). Its copy is still made: its
  // exact box drops the pairs whose bodies' boxes do not meet (on the 1,000-ball pile 4,894
  // pairs against 7,258 from the roots' boxes moved by the poses), and the exact tests of its PCS
  // read it.
  drawn_only.assign(ids.size(), 0);
  if (opt.stage == Stage::image && resident_route(opt)) {
    for (std::size_t k = 0; k < ids.size(); ++k) drawn_only[k] = pairs_of[k] > 0 && !(opt.self || bodies[ids[k]].self);
    for (std::size_t p = 0; p < pairs.size(); ++p)
      if (!resident_pair(p)) drawn_only[pairs[p].first] = drawn_only[pairs[p].second] = 0;
  }
  to_copy.clear();
  for (std::size_t k = 0; k < ids.size(); ++k) {
    Body& b = bodies[ids[k]];
    if (!b.world_frame || b.copy_valid || pairs_of[k] == 0) continue;
    if (!b.still && pairs_of[k] < kCopyPairs && !b.ill_conditioned)
      b.posed_this_frame();
    else
      to_copy.push_back(k);
  }
  // The copies over the lanes, and the trees of those a traversal will read (in two pairs or
  // more: one pair of a body just copied is scanned, plan_tasks()).
  parallel("copy", to_copy.size(), lanes, [&](std::size_t c, unsigned) {
    Body& b = bodies[ids[to_copy[c]]];
    b.ensure_copy();
    if (pairs_of[to_copy[c]] >= 2 && !drawn_only[to_copy[c]]) b.ensure_world_tree();
  });
  for (const std::size_t k : to_copy) {
    stats.vertices_transformed += bodies[ids[k]].world_copy.vertices.size();
    boxes[k] = bodies[ids[k]].world_box().grown(0.5 * opt.margin);
  }
  if (to_copy.empty()) return;
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const std::pair<std::size_t, std::size_t>& p) {
                               return !boxes[p.first].overlaps(boxes[p.second]);
                             }),
              pairs.end());
}

namespace {
// A split's node pair of bodies ida and idb, as a key for its cost from one frame to the next (a
// collision of two keys only mixes two estimates).
std::uint64_t split_key(std::size_t ida, std::size_t idb, const BvhNodePair& start) {
  return (std::uint64_t(ida) * 0x9E3779B97F4A7C15ull) ^ (std::uint64_t(idb) * 0xC2B2AE3D27D4EB4Full) ^
         (std::uint64_t(start.first) << 32 | start.second);
}
}  // namespace

// A split's node pairs ordered for the lanes: by their cost in the last frame (node pairs
// visited and couples found, from split_costs; a node pair new to the split counts as the
// split's mean), most first, then dealt: WorkerPool::for_each() starts lane l on the l-th of
// `lanes` contiguous ranges, so the l-th range gets the ordered items l, l + lanes, ... Each
// lane starts on its largest items and the small ones are left at the ranges' ends, where the
// lanes done first take them. (The split lists them level by level, neighbours in space
// together: the contact region, where the work is, falls in few of them, and a large item
// started last draws the loop out.)
void World::Impl::order_split(std::size_t ida, std::size_t idb, unsigned lanes) {
  split_order.clear();
  std::uint64_t known = 0, sum = 0;
  for (const BvhNodePair& start : split) {
    const std::uint64_t key = split_key(ida, idb, start);
    const auto it = std::lower_bound(split_costs.begin(), split_costs.end(), std::make_pair(key, std::uint32_t(0)));
    const bool found = it != split_costs.end() && it->first == key;
    split_order.push_back({found ? it->second : ~std::uint32_t(0), start});
    if (found) ++known, sum += it->second;
  }
  const std::uint32_t mean = known ? std::uint32_t(sum / known) : 0;
  for (auto& [cost, start] : split_order)
    if (cost == ~std::uint32_t(0)) cost = mean;
  // (std::sort, not std::stable_sort: that one takes a buffer from the heap every call.)
  std::sort(split_order.begin(), split_order.end(),
            [](const auto& x, const auto& y) { return x.first != y.first ? x.first > y.first : x.second < y.second; });
  split.clear();
  for (unsigned l = 0; l < lanes; ++l)
    for (std::size_t i = l; i < split_order.size(); i += lanes) split.push_back(split_order[i].second);
}

// Each split task's cost this frame (node pairs visited, couples found), for order_split() in
// the next.
void World::Impl::keep_split_costs(std::size_t used) {
  split_costs_next.clear();
  for (std::size_t k = 0; k < used; ++k) {
    const Task& t = tasks[k];
    const std::size_t p = t.pair;
    if (t.kind == TaskKind::small_pair || first_task[p + 1] - first_task[p] < 2 || (!untraversed.empty() && untraversed[p]))
      continue;
    // (A self task's couples are tested as its traversal finds them: `tested`, no candidates.)
    const std::uint64_t cost = std::uint64_t(t.visited) + t.candidates.size() + t.tested;
    split_costs_next.emplace_back(split_key(ids[pairs[p].first], ids[pairs[p].second], t.start),
                                  std::uint32_t(std::min<std::uint64_t>(cost, ~std::uint32_t(0) - 1)));
  }
  std::sort(split_costs_next.begin(), split_costs_next.end());
  split_costs.swap(split_costs_next);
}

// The traversals' tasks: per pair, one task, or (several lanes) the node pairs of its first
// levels; a self pair one traversal of the body's own tree (none for a rigid body's cache); two
// small world-space bodies, one of them moved, one scan when each moved one is in no other pair
// (Body::small()). Returns the tasks used.
std::size_t World::Impl::plan_tasks(unsigned lanes) {
  std::size_t used = 0;
  count_pairs();  // again, after copy_paired()'s drops
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    Body& a = bodies[ids[pairs[p].first]];
    Body& b = bodies[ids[pairs[p].second]];
    TaskKind kind = TaskKind::nodes;
    if (&a == &b) {
      kind = TaskKind::self;
      split.clear();
      // A large body's self traversal split into node pairs for the lanes, as a pair's (when
      // few pairs share the lanes); its contacts are sorted once gathered (self_pair()).
      if (!(a.is_rigid && a.self_cached)) {
        if (lanes > 1 && pairs.size() < kSplitPairsPerLane * std::size_t(lanes) &&
            a.local().triangles.size() >= kSplitTriangles) {
          bvh_self_split(a.tree, kSplitNodePairsPerLane * std::size_t(lanes), split, split_scratch);
          order_split(ids[pairs[p].first], ids[pairs[p].second], lanes);
        } else {
          split.assign(1, BvhNodePair{0u, 0u});
        }
      }
    } else if (a.small() && b.small() && a.world_mesh() && b.world_mesh() && (a.moved || b.moved) &&
               (!a.moved || pairs_of[pairs[p].first] == 1) && (!b.moved || pairs_of[pairs[p].second] == 1)) {
      kind = TaskKind::small_pair;
      split.assign(1, BvhNodePair{0u, 0u});
    } else if (drawn_only[pairs[p].first] && drawn_only[pairs[p].second]) {
      // The resident route's: not traversed (mark_untraversed()); a large pair's PCS shared by
      // one task a lane for the exact tests (resident_image_pairs()).
      const bool large = lanes > 1 && pairs.size() < kSplitPairsPerLane * std::size_t(lanes) &&
                         a.local().triangles.size() + b.local().triangles.size() >= kSplitTriangles;
      split.assign(large ? lanes : 1, BvhNodePair{0u, 0u});
    } else {
      a.ensure_world_tree();
      b.ensure_world_tree();
      // Few pairs each split into node pairs for the lanes (kSplitPairsPerLane); a small pair
      // (under kSplitTriangles between its bodies) is one task whatever the lanes; so is a pair
      // with a refit put off (its tree is last frame's: the task starts at the roots).
      if (lanes > 1 && pairs.size() < kSplitPairsPerLane * std::size_t(lanes) && a.tree_current() && b.tree_current() &&
          a.local().triangles.size() + b.local().triangles.size() >= kSplitTriangles) {
        bvh_split(a.frame_tree(), b.frame_tree(), BvhRelation::between(a.frame_pose(), b.frame_pose()),
                  kSplitNodePairsPerLane * std::size_t(lanes), split, split_scratch);
        order_split(ids[pairs[p].first], ids[pairs[p].second], lanes);
      } else {
        split.assign(1, BvhNodePair{0u, 0u});
      }
    }
    for (const BvhNodePair& start : split) {
      if (used == tasks.size()) tasks.emplace_back();
      Task& t = tasks[used++];
      t.pair = p;
      t.kind = kind;
      t.start = start;
    }
  }
  return used;
}

// Once a frame, after the trees are brought to it: each paired body's tree in its traversal's
// frame syncs its wide view when it has not changed since the last frame (Bvh::keep_wide_if_still():
// a still body's trees are traversed 4-wide, a tree refitted every frame stays binary).
void World::Impl::keep_wide_views() {
  for (std::size_t k = 0; k < ids.size(); ++k) {
    Body& b = bodies[ids[k]];
    if (pairs_of[k] == 0 || (b.world_frame && !b.world_tree_fresh)) continue;
    b.frame_tree().keep_wide_if_still();
  }
}

// Every task's candidates (self tasks: their contacts, each couple tested as the traversal
// reaches it, adjacent couples dropped), over the lanes.
void World::Impl::traverse(std::size_t used, unsigned lanes) {
  parallel("traverse", used, lanes, [&](std::size_t k, unsigned lane) {
    if (!untraversed.empty() && untraversed[tasks[k].pair]) {  // the image stage's alone (resident_image_pairs())
      Task& t = tasks[k];
      t.candidates.clear();
      t.contacts.clear();
      t.transformed = t.tested = t.visited = 0;
      return;
    }
    traverse_task(k, lane);
  });
}

// Task k's traversal on lane `lane`'s stacks.
void World::Impl::traverse_task(std::size_t k, unsigned lane) {
  Task& t = tasks[k];
  const Body& a = bodies[ids[pairs[t.pair].first]];
  const Body& b = bodies[ids[pairs[t.pair].second]];
  t.candidates.clear();
  t.contacts.clear();
  t.transformed = 0;
  t.tested = 0;
  if (t.kind == TaskKind::self) {  // in the body's own frame
    const Mesh& m = a.local();
    const std::uint32_t* rep = a.rep_adjacency == SelfAdjacency::index ? nullptr : a.rep.data();  // index: the identity
    ContactTest test{detail};
    const exact_detail::TestInto test_left{test, t.contacts};
    // Couples sharing a corner dropped in the traversal, eight at once; the rest tested a block
    // at a time (as test_task_as()).
    ApartBlock& block = lane_scratch[lane]->apart;
    t.visited = bvh_self_traverse_apart(a.tree, rep, t.start, self_stacks[lane].v, [&](std::uint32_t x, std::uint32_t y) {
      ++t.tested;
      if (y < x) std::swap(x, y);
      block.put(x, y, corners(m, x), corners(m, y));
      if (block.full()) block.drain(test_left);
    });
    block.drain(test_left);
    return;
  }
  if (t.kind == TaskKind::small_pair) {  // as the frame API's exact path: one culling round, a sweep
    const Mesh& ma = *a.world_mesh();
    const Mesh& mb = *b.world_mesh();
    LaneScratch& s = *lane_scratch[lane];
    cull_to_contact_region(ma, mb, intersection(boxes[pairs[t.pair].first], boxes[pairs[t.pair].second]), s.cull, 1);
    if (!s.cull.box.empty()) box_overlap_pairs(ma, s.cull.kept_a, mb, s.cull.kept_b, t.candidates, &s.boxes);
    t.visited = 0;
    return;
  }
  bvh_detail::CoupleKeys take(t.candidates);  // the couples as keys, a leaf lane's at once
  // Two trees in one frame (two world-space copies, or one pose for both) need no relation.
  if ((a.world_frame && b.world_frame) || a.frame_pose().matrix() == b.frame_pose().matrix()) {
    t.visited = bvh_traverse_same_frame(a.frame_tree(), b.frame_tree(), t.start, self_stacks[lane].v, take);
  } else {
    const BvhRelation rel = BvhRelation::between(a.frame_pose(), b.frame_pose());
    t.visited = rel.identity ? bvh_traverse_same_frame(a.frame_tree(), b.frame_tree(), t.start, self_stacks[lane].v, take)
                             : bvh_traverse(a.frame_tree(), b.frame_tree(), rel, t.start, stacks[lane].v, take);
  }
  take.finish();
}

// Per pair: its result started, its tasks found (first_task), its route: self pairs and
// Stage::exact to the exact path, Stage::image to the image stage, else the router with the
// World's exact model (world_exact_cost(): per candidate couple) against the stage's.
void World::Impl::route_pairs(const DetectOptions& opt, std::size_t used, FrameResult& out) {
  out.pairs.resize(pairs.size());
  first_task.assign(pairs.size() + 1, used);
  for (std::size_t k = used; k-- > 0;) first_task[tasks[k].pair] = k;
  for (std::size_t p = pairs.size(); p-- > 0;)
    if (first_task[p] > first_task[p + 1]) first_task[p] = first_task[p + 1];
  const StageCost image_cost = stage->router_image_cost();
  const StageCost exact_cost = world_exact_cost();
  const int tile = opt.resolution > 0 ? opt.resolution : opt.budget;
  to_image.assign(pairs.size(), 0);
  // Each pair on its own (over the lanes: a pile's thousands), the counts summed after.
  parallel("route", pairs.size(), frame_lanes, [&](std::size_t p, unsigned) {
    PairResult& r = out.pairs[p];
    std::vector<Contact> colliding = std::move(r.colliding);  // its storage reused frame to frame
    colliding.clear();
    r = PairResult{};
    r.colliding = std::move(colliding);
    r.object_a = ids[pairs[p].first];
    r.object_b = ids[pairs[p].second];
    r.roi = r.region = intersection(boxes[pairs[p].first], boxes[pairs[p].second]);
    std::size_t n = 0;
    for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) n += tasks[k].candidates.size();
    r.candidates = n;
    if (r.object_a == r.object_b) {  // self: the exact path always (docs/design.md)
      r.exact_stage = true;
      // Not routed; predicted by the World's model from the couples its traversal tested, as
      // the frame API predicts its self pairs (docs/router.md).
      std::size_t tested = 0;
      for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) tested += tasks[k].tested;
      if (opt.stage == Stage::automatic) r.predicted_exact_ms = exact_cost.predict_ms(double(tested), 0.0);
      return;
    }
    // A margin too wide for the image stage: the exact path, whatever the stage asked.
    if (opt.stage != Stage::exact && margin_too_wide_for_image(opt, r.roi)) {
      r.exact_stage = r.margin_fallback = true;
      return;
    }
    if (!untraversed.empty() && untraversed[p]) {  // Stage::image, resident: not traversed
      to_image[p] = 1;
      return;
    }
    if (n == 0) return;  // no couple of boxes overlaps: no contact, nothing to test
    // The image stage draws at most the candidates' triangles: at most 2n, counted as n.
    const Route route = route_pair(opt, exact_cost, image_cost, 0.0, double(n), tile);
    r.predicted_exact_ms = route.predicted_exact_ms;
    r.predicted_image_ms = route.predicted_image_ms;
    r.exact_stage = route.exact;
    to_image[p] = !route.exact;
  });
  for (std::size_t k = 0; k < used; ++k) {
    stats.node_pairs += tasks[k].visited;
    stats.candidates += tasks[k].candidates.size();
  }
}

// The exact path's tests over the same tasks (a self task's during its traversal).
void World::Impl::test_candidates(const DetectOptions& opt, std::size_t used, unsigned lanes) {
  parallel("test", used, lanes, [&](std::size_t k, unsigned lane) {
    Task& t = tasks[k];
    if (t.candidates.empty() || to_image[t.pair]) return;
    const Body& a = bodies[ids[pairs[t.pair].first]];
    const Body& b = bodies[ids[pairs[t.pair].second]];
    if (t.kind == TaskKind::self) return;
    if (t.kind == TaskKind::small_pair) {  // the sweep's pairs: distinct, boxes overlapping, world meshes at hand
      sort_unique_pairs(t.candidates, lane_scratch[lane]->sorted);
      narrow_phase(*a.world_mesh(), *b.world_mesh(), t.candidates, t.contacts, /*boxes_overlap=*/true,
                   opt.max_contacts, opt.contacts);
      return;
    }
    test_task(a, b, opt, t, lane_scratch[lane]->apart);
  });
}

// A traversal task's candidates in traversal order (deterministic; the pair's contacts are
// sorted after): sorting them first cost 2-12% of a frame and bought nothing. A posed pair's
// couples have their world boxes compared first (exact comparisons of the same doubles the test
// reads), then the exact test; a pair in one frame goes to the exact test at once (its
// traversal compared the triangles' own boxes, rounded outward).
// A posed body's corners cost a transform each: there a triangle's world corners and box are
// computed once for the run of couples it is in (the traversal reports a triangle of A with
// each of B's it meets in a row: A's kept from the previous couple; B's come back within a leaf
// pair: kept in a small table by triangle index). On the rigid 1.3M-triangle spheres 57k couples
// read 14k triangles of A and 13k of B, and the tests took 0.85x their time. Bodies in world
// space read their corners as they are: there the branches on the kept triangles cost more than
// the reads (the 1,000-ball pile's tests 1.07x their time kept).
void World::Impl::test_task(const Body& a, const Body& b, const DetectOptions& opt, Task& t, ApartBlock& block) {
  const std::size_t moved_a = a.is_rigid && !a.world_frame ? 3 : 0, moved_b = b.is_rigid && !b.world_frame ? 3 : 0;
  if (moved_a || moved_b)
    test_task_as<true>(a, b, opt, t, block);
  else
    test_task_as<false>(a, b, opt, t, block);
}

template <bool kKeep>
void World::Impl::test_task_as(const Body& a, const Body& b, const DetectOptions& opt, Task& t, ApartBlock& block) {
  const Mesh& ma = a.local();
  const Mesh& mb = b.local();
  // The candidates' data is read in an order the hardware cannot guess: their triangles are
  // asked for kAhead candidates ahead, their corners kAhead / 2 ahead. It pays where other work
  // evicted the data (as in the bench, where the methods take turns) and costs nothing on warm
  // data.
  constexpr std::size_t kAhead = 32;
  const Vec3* va = a.world_vertices();
  const Vec3* vb = b.world_vertices();
  const std::size_t n = t.candidates.size();
  const std::size_t moved_a = a.is_rigid && !a.world_frame ? 3 : 0, moved_b = b.is_rigid && !b.world_frame ? 3 : 0;
  std::size_t transformed = 0;
  struct Count {  // into the task once, also on the early return
    Task& t;
    const std::size_t& n;
    ~Count() { t.transformed += n; }
  } count{t, transformed};
  struct Corners {  // a triangle's world corners and their box
    std::uint32_t tri = std::uint32_t(-1);
    TriangleCorners c;
    Vec3 lo, hi;
    void load(const Body& body, const Mesh& m, std::uint32_t k) {
      const Tri& f = m.triangles[k];
      c = {body.world(f[0]), body.world(f[1]), body.world(f[2])};
      if (kKeep) {
        lo = c[0].cwiseMin(c[1]).cwiseMin(c[2]);
        hi = c[0].cwiseMax(c[1]).cwiseMax(c[2]);
      }
      tri = k;
    }
  };
  constexpr std::uint32_t kKeptB = kKeep ? 16 : 1;  // B's table: a leaf's eight triangles and the next leaf's
  Corners x, kept_b[kKeptB];
  ContactTest test{opt.contacts};
  // The couples go to the exact test a block at a time, after the block's planes' test in SIMD
  // lanes (exact_detail::ApartBlock: the exact test's first step, four couples at once) put
  // aside those certainly apart; the rest in candidate order, until the task has enough
  // (t.contacts starts empty).
  const exact_detail::TestInto test_left{test, t.contacts, opt.max_contacts ? opt.max_contacts : std::size_t(-1)};
  for (std::size_t k = 0; k < n; ++k) {
    if (k + kAhead < n) {
      const std::uint64_t f = t.candidates[k + kAhead];
      __builtin_prefetch(&ma.triangles[pair_a(f)]);
      __builtin_prefetch(&mb.triangles[pair_b(f)]);
    }
    if (k + kAhead / 2 < n) {
      const std::uint64_t f = t.candidates[k + kAhead / 2];
      const Tri& pa = ma.triangles[pair_a(f)];
      const Tri& pb = mb.triangles[pair_b(f)];
      for (int i = 0; i < 3; ++i) {
        __builtin_prefetch(&va[pa[i]]);
        __builtin_prefetch(&vb[pb[i]]);
      }
    }
    const std::uint64_t c = t.candidates[k];
    const std::uint32_t ta = pair_a(c), tb = pair_b(c);
    if (!kKeep) {  // world space: the corners as they are
      const Tri& fa = ma.triangles[ta];
      const Tri& fb = mb.triangles[tb];
      block.put(ta, tb, va[fa[0]], va[fa[1]], va[fa[2]], vb[fb[0]], vb[fb[1]], vb[fb[2]]);
    } else {
      Corners& y = kept_b[tb % kKeptB];
      if (x.tri != ta) {
        x.load(a, ma, ta);
        transformed += moved_a;
      }
      if (y.tri != tb) {
        y.load(b, mb, tb);
        transformed += moved_b;
      }
      // Posed trees report couples whose boxes were carried through a pose (boxes of boxes):
      // their own world boxes first. (Two trees in one frame reported couples whose float boxes,
      // rounded outward, overlap: the exact test decides at once.)
      if ((x.hi.array() < y.lo.array()).any() || (y.hi.array() < x.lo.array()).any()) continue;
      block.put(ta, tb, x.c, y.c);
    }
    if (block.full() && !block.drain(test_left)) return;
  }
  block.drain(test_left);
}

// Each exact pair's contacts from its tasks, sorted (self pairs through self_pair()).
void World::Impl::gather_contacts(FrameResult& out) {
  for (std::size_t p = 0; p < pairs.size(); ++p) {  // the counts
    const PairResult& r = out.pairs[p];
    if (r.object_a != r.object_b && (r.candidates == 0 || to_image[p] || peeled_resident[p])) continue;
    ++out.rois_exact;
    if (r.object_a != r.object_b)
      for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k) stats.vertices_transformed += tasks[k].transformed;
  }
  // The contacts, pair by pair over the lanes (each sorted: a pile's thousands of pairs).
  parallel("gather", pairs.size(), frame_lanes, [&](std::size_t p, unsigned lane) {
    PairResult& r = out.pairs[p];
    ContactSortScratch& scratch = lane_scratch[lane]->contacts;
    if (r.object_a == r.object_b) {
      self_pair(bodies[r.object_a], first_task[p], first_task[p + 1], r, scratch);
      return;
    }
    if (r.candidates == 0 || to_image[p]) return;
    if (first_task[p + 1] - first_task[p] == 1 && r.colliding.empty()) {
      // One task: its contacts taken whole (the two vectors trade storage, no copy).
      r.colliding.swap(tasks[first_task[p]].contacts);
    } else {
      for (std::size_t k = first_task[p]; k < first_task[p + 1]; ++k)
        r.colliding.insert(r.colliding.end(), tasks[k].contacts.begin(), tasks[k].contacts.end());
    }
    sort_contacts(r.colliding, scratch);
  });
}

// Relations (containment where no contact) and, asked for, volumes: world meshes made only for
// the pairs that need them.
void World::Impl::relate(const DetectOptions& opt, FrameResult& out) {
  body_boxes.assign(bodies.size(), Aabb{});
  for (std::size_t i = 0; i < ids.size(); ++i) body_boxes[ids[i]] = boxes[i];
  world_meshes.clear();
  // The pairs related from their contacts alone, over the lanes (a pile's thousands); those that
  // read a mesh (made here on demand) after, on this thread.
  if (!relate_lanes.for_pairs)
    relate_lanes.for_pairs = [this](std::size_t n, const std::function<void(std::size_t)>& fn) {
      parallel("relate", n, frame_lanes, [&](std::size_t i, unsigned) { fn(i); });
    };
  relate_pairs(
      out.pairs,
      [&](std::size_t id) -> const Mesh& {
        const Body& b = bodies[id];
        if (const Mesh* m = b.world_mesh()) return *m;
        auto it = world_meshes.find(id);
        if (it == world_meshes.end()) {
          Mesh m = *b.shape;
          for (Vec3& v : m.vertices) v = b.pose * v;
          it = world_meshes.emplace(id, std::move(m)).first;
        }
        return it->second;
      },
      body_boxes, opt, nullptr, &relate_lanes);
}

}  // namespace peelcd
