#include "pair_plan.h"

#include "peelcd/core/exact/self.h"

#include "../exact/apart_block.h"
#include "../exact/bvh_traverse.h"

#include <algorithm>
#include <numeric>

namespace peelcd::detail {

void FramePlan::find_pairs(const ObjectRefs& objects, const DetectOptions& opt, const std::vector<IndexPair>* only) {
  boxes.clear();
  for (std::size_t i = 0; i < objects.size(); ++i) boxes.push_back(bounds(objects[i].mesh));
  if (opt.margin > 0.0)  // proximity: boxes within the margin of each other make a pair
    for (Aabb& b : boxes)
      b = b.grown(0.5 * opt.margin);
  overlapping_pairs(boxes, pairs, sweep_);
  if (only)
    pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                               [&](const IndexPair& p) { return !std::binary_search(only->begin(), only->end(), p); }),
                pairs.end());
  bool any_self = false;
  for (std::size_t i = 0; i < objects.size(); ++i)
    if ((opt.self || objects[i].self) && objects[i].mesh.triangles.size() >= 2) {
      pairs.emplace_back(i, i);
      any_self = true;
    }
  if (any_self) std::sort(pairs.begin(), pairs.end());
}

void FramePlan::reset(std::size_t i, const ObjectRefs& objects, int tile) {
  PairPlan& p = plans[i];
  p.a = pairs[i].first;
  p.b = pairs[i].second;
  p.roi = intersection(boxes[p.a], boxes[p.b]);
  p.region = p.roi;
  p.in_roi_a = p.in_roi_b = 0;
  p.scanned = objects[p.a].mesh.triangles.size() + objects[p.b].mesh.triangles.size();
  p.culled_out = false;
  p.tile = tile;
  p.route = Route{};
  p.margin_fallback = false;
  p.kept_a.clear();
  p.kept_b.clear();
}

namespace {
void cull_pair(const ObjectRefs& objects, PairPlan& p, int rounds, double margin, ContactCull& cull) {
  cull_to_contact_region(objects[p.a].mesh, objects[p.b].mesh, p.roi, cull, rounds, margin);
  p.region = cull.box;
  p.in_roi_a = cull.stats.in_roi_a;
  p.in_roi_b = cull.stats.in_roi_b;
  p.culled_out = cull.box.empty();
  p.kept_a.assign(cull.kept_a.begin(), cull.kept_a.end());
  p.kept_b.assign(cull.kept_b.begin(), cull.kept_b.end());
  p.median_edge = cull.median_edge;
}
}  // namespace

void FramePlan::plan(const ObjectRefs& objects, const DetectOptions& opt, PairLoop& loop) {
  if (plans.size() < pairs.size()) plans.resize(pairs.size());
  if (self_trees_.size() < objects.size()) self_trees_.resize(objects.size());
  const int equal = opt.resolution > 0 ? opt.resolution : tile_resolution(opt.budget, pairs.size());
  const int first_rounds = opt.stage == Stage::image ? kMaxCullRounds : 1;
  // A self pair of a large mesh whose couples are tested while planning is planned after the
  // pair loop, its traversal spread over the lanes (as the World's, docs/performance.md).
  spread_self_.clear();
  if (opt.threads != 1 && opt.stage != Stage::image && opt.max_contacts == 0)
    for (std::size_t i = 0; i < pairs.size(); ++i)
      if (pairs[i].first == pairs[i].second && objects[pairs[i].first].mesh.triangles.size() >= kSpreadSelfTriangles)
        spread_self_.push_back(i);
  if (!spread_self_.empty() && loop.lanes(opt) == 1) spread_self_.clear();  // (threads 0 on one core)
  loop.run(pairs.size(), opt, [&](std::size_t i, PairLane& lane) {
    reset(i, objects, equal);
    PairPlan& p = plans[i];
    if (p.a == p.b) {
      if (!std::binary_search(spread_self_.begin(), spread_self_.end(), i)) plan_self(objects[p.a].mesh, opt, p, self_trees_[p.a]);
    } else if (opt.cull != Cull::contact) {
      plan_box(objects, opt, p);
    } else {
      cull_pair(objects, p, first_rounds, opt.margin, lane.cull);
    }
  });
  for (const std::size_t i : spread_self_) plan_self(objects[plans[i].a].mesh, opt, plans[i], self_trees_[plans[i].a], &loop);
  share_budget(opt);
  route(opt);
  if (opt.stage != Stage::automatic || opt.cull != Cull::contact) return;
  bool any_image = false;
  for (std::size_t i = 0; i < pairs.size(); ++i) any_image = any_image || plans[i].peeled();
  if (!any_image) return;
  loop.run(pairs.size(), opt, [&](std::size_t i, PairLane& lane) {
    PairPlan& p = plans[i];
    if (p.peeled() && p.a != p.b) cull_pair(objects, p, kMaxCullRounds, opt.margin, lane.cull);
  });
  share_budget(opt);  // the same ROIs share it: the image ROIs' needs now final
}

// Cull::box: the router and the exact path need the triangles touching the ROI (the image stage
// alone peels the whole box).
void FramePlan::plan_box(const ObjectRefs& objects, const DetectOptions& opt, PairPlan& p) {
  if (opt.stage == Stage::image) return;
  // Proximity: a triangle within the margin of the other object touches the ROI grown by half.
  const Aabb roi = p.roi.grown(0.5 * opt.margin);
  triangles_touching(objects[p.a].mesh, roi, p.kept_a);
  triangles_touching(objects[p.b].mesh, roi, p.kept_b);
  p.in_roi_a = p.kept_a.size();
  p.in_roi_b = p.kept_b.size();
  p.culled_out = p.kept_a.empty() || p.kept_b.empty();
}

namespace {

// The self couples under node pair `start` of `tree`'s traversal against itself (adjacent ones
// dropped), each tested as the traversal finds it (the planes' test a block at a time first, as
// narrow_phase()): the contacts appended to `contacts` (one run of tests: ContactTest), both
// triangles of each couple marked. Returns the couples.
std::size_t test_self_couples(const Mesh& mesh, const Bvh& tree, const std::uint32_t* rep, BvhNodePair start,
                              std::vector<BvhNodePair>& stack, ContactDetail detail, std::vector<Contact>& contacts,
                              std::vector<std::uint8_t>& marks) {
  ContactTest test{detail};
  const exact_detail::TestInto test_left{test, contacts};
  exact_detail::ApartBlock block;
  std::size_t count = 0;
  bvh_self_traverse_apart(tree, rep, start, stack, [&](std::uint32_t t, std::uint32_t u) {
    if (u < t) std::swap(t, u);
    marks[t] = marks[u] = 1;
    ++count;
    block.put(t, u, corners(mesh, t), corners(mesh, u));
    if (block.full()) block.drain(test_left);
  });
  block.drain(test_left);
  return count;
}

}  // namespace

// A self pair's plan: its ROI is the object's box; its candidates are found by its tree against
// itself (self_overlap_pairs(); the tree kept for the object's next frames, SelfTree), which is
// its culling too: the triangles kept are those in some candidate, the region their box. The
// image stage peels them as both objects.
void FramePlan::plan_self(const Mesh& mesh, const DetectOptions& opt, PairPlan& p, SelfTree& tree, PairLoop* spread) {
  p.scanned = p.in_roi_a = p.in_roi_b = mesh.triangles.size();
  vertex_representatives(mesh, opt.self_adjacency, p.rep);
  p.self_candidates.clear();
  p.self_contacts.clear();
  // The kept triangles, ascending: marked, then read in order (the cloth's 736k couples: a sort
  // of their 1.5M ends cost a fifth of the frame).
  p.marks.assign(mesh.triangles.size(), 0);
  // A self pair takes the exact path unless peeled (FramePlan::route()): each couple is tested
  // as the traversal finds it, as in the World (no list of candidates; the exact path takes the
  // contacts). A limit on the contacts keeps the first in (tri_a, tri_b) order, as every path
  // gives them: the candidates are listed and sorted first.
  p.self_tested = opt.stage != Stage::image && opt.max_contacts == 0;
  if (p.self_tested && spread) {
    // The traversal split into node pairs (bvh_self_split()) over the lanes, each lane's contacts,
    // marks and count merged after (the contacts are sorted on the exact path).
    const unsigned lanes = spread->lanes(opt);
    tree.update(mesh, lanes, [&](std::size_t n, const auto& fn) {  // a build in subtrees over the lanes
      spread->run(n, opt, [&](std::size_t k, PairLane&) { fn(k); });
    });
    const std::uint32_t* rep = representatives_or_null(p.rep);
    bvh_self_split(tree.tree, kSelfNodePairsPerLane * lanes, self_split_, self_split_scratch_);
    spread->each_lane([&](PairLane& l) {
      l.self_contacts.clear();
      l.self_marks.assign(mesh.triangles.size(), 0);
      l.self_count = 0;
    });
    spread->run(self_split_.size(), opt, [&](std::size_t k, PairLane& lane) {
      lane.self_count += test_self_couples(mesh, tree.tree, rep, self_split_[k], lane.self_stack, opt.contacts,
                                           lane.self_contacts, lane.self_marks);
    });
    p.self_count = 0;
    spread->each_lane([&](PairLane& l) {
      p.self_contacts.insert(p.self_contacts.end(), l.self_contacts.begin(), l.self_contacts.end());
      for (std::size_t t = 0; t < l.self_marks.size(); ++t) p.marks[t] |= l.self_marks[t];
      p.self_count += l.self_count;
    });
  } else if (p.self_tested) {
    tree.update(mesh);
    p.self_count = test_self_couples(mesh, tree.tree, representatives_or_null(p.rep), BvhNodePair{0u, 0u}, tree.stack,
                                     opt.contacts, p.self_contacts, p.marks);
  } else {
    self_overlap_pairs(mesh, tree, p.rep, p.self_candidates);
    if (opt.max_contacts) std::sort(p.self_candidates.begin(), p.self_candidates.end());
    p.self_count = p.self_candidates.size();
    for (const std::uint64_t c : p.self_candidates) p.marks[pair_a(c)] = p.marks[pair_b(c)] = 1;
  }
  for (std::uint32_t t = 0; t < p.marks.size(); ++t)
    if (p.marks[t]) p.kept_a.push_back(t);
  p.kept_b = p.kept_a;
  p.culled_out = p.kept_a.empty();
  p.region = Aabb{};
  std::vector<double> edges;
  for (const std::uint32_t t : p.kept_a) {
    const Tri& f = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) p.region.extend(mesh.vertices[f[c]]);
    edges.push_back((mesh.vertices[f[1]] - mesh.vertices[f[0]]).norm());
  }
  p.median_edge = 0.0;
  if (!edges.empty()) {
    std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
    p.median_edge = edges[edges.size() / 2];
  }
  if (opt.cull == Cull::box && !p.culled_out) {  // the image stage peels the whole box
    p.region = p.roi;
    p.kept_a.resize(mesh.triangles.size());
    std::iota(p.kept_a.begin(), p.kept_a.end(), 0u);
    p.kept_b = p.kept_a;
  }
}

// With Cull::contact and a shared budget: each ROI's tile by need (allocate_tiles()), among the
// ROIs not culled out.
void FramePlan::share_budget(const DetectOptions& opt) {
  if (opt.cull != Cull::contact || opt.resolution != 0) return;
  const double edge_texels = edge_texels_of(opt);
  needs_.clear();
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const PairPlan& p = plans[i];
    if (!p.culled_out) needs_.push_back(edge_tile_resolution(opt.budget, p.region, p.median_edge, edge_texels));
  }
  allocate_tiles(opt.budget, needs_, tiles_);
  std::size_t next = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (!plans[i].culled_out) plans[i].tile = tiles_[next++];
}

// Each ROI through the router (planner.h): the work is the triangles kept, the scan both
// objects' triangles. A self pair takes the exact path, as in the World: the image model was
// never fitted to a ROI peeled as both objects, and underpredicts it about 3x (docs/router.md).
// Its exact prediction is by its candidate couples, known from planning (the World's model: a
// cloth's couples grow with its folds, not its triangles).
void FramePlan::route(const DetectOptions& opt) {
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    PairPlan& p = plans[i];
    if (p.culled_out) continue;
    // A margin too wide for the image stage: the exact path, whatever the stage asked (its
    // triangles are the culled ones: with Cull::box under Stage::image none are listed).
    p.margin_fallback = p.a != p.b && opt.stage != Stage::exact && opt.cull == Cull::contact &&
                        margin_too_wide_for_image(opt, p.roi);
    if (p.margin_fallback) {
      p.route = Route{};
      p.route.exact = true;
      continue;
    }
    if (opt.stage == Stage::image) continue;
    p.route = route_pair(opt, exact_cost, image_cost, double(p.scanned), double(p.kept_a.size() + p.kept_b.size()),
                         p.tile);
    if (p.a == p.b && opt.stage == Stage::automatic) {
      p.route.predicted_exact_ms = route_pair(opt, world_exact_cost(), image_cost, double(p.scanned),
                                              double(p.self_count), p.tile)
                                       .predicted_exact_ms;
      p.route.exact = true;
    }
  }
}

std::pair<double, double> make_view_job(const ObjectRefs& objects, const FramePlan& frame_plan, std::size_t pair_index,
                                        const DetectOptions& opt, const ViewFrame& frame, int v, double& epsilon,
                                        std::vector<std::uint32_t>& tris_a, std::vector<std::uint32_t>& tris_b,
                                        PeelJob& job) {
  const PairPlan& plan = frame_plan.plans[pair_index];
  const std::size_t ia = plan.a, ib = plan.b;
  const bool contact = opt.cull == Cull::contact;
  job.view = make_padded_roi_view(plan.region, frame_plan.boxes[ia], frame_plan.boxes[ib], frame, plan.tile);
  if (v == 0) epsilon = opt.epsilon > 0.0 ? opt.epsilon : job.view.texel();
  const double grow = opt.conservative ? 0.5 * opt.margin : 0.0;
  const double min_a = triangles_in_view(objects[ia].mesh, job.view, contact ? &plan.kept_a : nullptr, tris_a, grow);
  const double min_b = triangles_in_view(objects[ib].mesh, job.view, contact ? &plan.kept_b : nullptr, tris_b, grow);
  job.objects[0] = &objects[ia];
  job.objects[1] = &objects[ib];
  job.pair_index = pair_index;
  job.view_index = v;
  job.ids = opt.ids;
  job.peel = opt.peel;
  job.epsilon = epsilon;
  job.slope = opt.slope;
  job.first = min_a > min_b ? 0 : 1;  // the farther object first; ties: B first
  job.capture = false;
  job.conservative = opt.conservative;
  job.grow = grow;
  return {min_a, min_b};
}

}  // namespace peelcd::detail
