// The trace of one frame and the walk of one pair through it (peelcd/oracle/explain.h); the
// reports (JSON, text, page) are explain_report.cpp.
#include "peelcd/oracle/explain.h"

#include "explain_view.h"
#include "explain_words.h"

#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/image/kbuffer.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/core/exact/self.h"
#include "peelcd/io/error.h"
#include "peelcd/io/options_json.h"
#include "peelcd/io/output.h"
#include "peelcd/oracle/dump.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
#include <sstream>

namespace peelcd::oracle {
namespace {

using texel::as_float;

using words::g;
using words::object_word;

// The IDs of `mesh` whose triangle set (IdMap) holds triangle t.
std::set<std::uint32_t> ids_standing_for(const Mesh& mesh, const IdMap& map, std::uint32_t t) {
  std::set<std::uint32_t> out;
  std::vector<std::uint32_t> ids = {t};
  for (int k = 0; k < 3; ++k) ids.push_back(mesh.triangles[t][k]);
  for (const std::uint32_t id : ids)
    if (id < map.id_count() && std::find(map.begin(id), map.end(id), t) != map.end(id)) out.insert(id);
  return out;
}

const char* verdict_text(Verdict v) {
  switch (v) {
    case Verdict::found: return "found";
    case Verdict::found_exact: return "found by the exact CPU path";
    case Verdict::no_roi: return "the objects' boxes do not overlap";
    case Verdict::culled: return "culled";
    case Verdict::edge_on: return "edge-on, no fragment";
    case Verdict::sub_texel: return "between texel centres";
    case Verdict::separated: return "separated by a layer of the same object";
    case Verdict::above_epsilon: return "depth difference above the threshold";
    case Verdict::not_located: return "no texel explains it";
    case Verdict::no_contact: return "no contact";
  }
  return "?";
}

}  // namespace

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::found: return "found";
    case Verdict::found_exact: return "found_exact";
    case Verdict::no_roi: return "no_roi";
    case Verdict::culled: return "culled";
    case Verdict::edge_on: return "edge_on";
    case Verdict::sub_texel: return "sub_texel";
    case Verdict::separated: return "separated";
    case Verdict::above_epsilon: return "above_epsilon";
    case Verdict::not_located: return "not_located";
    case Verdict::no_contact: return "no_contact";
  }
  return "?";
}

PairQuery parse_pair_query(const std::string& text, const std::vector<Object>& objects) {
  const auto fail = [&](const std::string& problem) {
    throw InputError("peelcd: --pair '" + text + "': " + problem +
                     " (expected OBJ_A:TRI_A,OBJ_B:TRI_B, OBJ a name or an index)");
  };
  const std::size_t comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos) fail("not two items");
  const auto side = [&](const std::string& item, std::size_t& object, std::uint32_t& tri) {
    const std::size_t colon = item.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == item.size()) fail("'" + item + "' is not OBJ:TRI");
    const std::string name = item.substr(0, colon), number = item.substr(colon + 1);
    bool found = false;
    for (std::size_t i = 0; i < objects.size() && !found; ++i)
      if (objects[i].name == name) object = i, found = true;
    if (!found) {
      if (name.find_first_not_of("0123456789") != std::string::npos || name.size() > 9)
        fail("no object named '" + name + "'");
      object = std::stoul(name);
      if (object >= objects.size())
        fail("object index " + name + " is out of range (" + std::to_string(objects.size()) + " objects)");
    }
    if (number.find_first_not_of("0123456789") != std::string::npos || number.size() > 10)
      fail("'" + number + "' is not a triangle index");
    const unsigned long long t = std::stoull(number);
    const std::size_t count = objects[object].mesh.triangles.size();
    if (t >= count)
      fail("triangle " + number + " is out of range: '" + objects[object].name + "' has " + std::to_string(count) +
           " triangles");
    tri = std::uint32_t(t);
  };
  PairQuery q;
  side(text.substr(0, comma), q.object_a, q.tri_a);
  side(text.substr(comma + 1), q.object_b, q.tri_b);
  if (q.object_a == q.object_b && q.tri_a == q.tri_b) fail("a triangle with itself is not a pair");
  return q;
}

FrameTrace::FrameTrace(Detector& detector, const std::vector<Object>& objects, const DetectOptions& options)
    : objects_(objects), options_(options) {
  detector.capture_layers(&captured_);
  try {
    detector.detect(objects, options, result_);
  } catch (...) {
    detector.capture_layers(nullptr);
    throw;
  }
  detector.capture_layers(nullptr);
  backend_ = detector.stage().backend();
  renderer_ = result_.renderer;
}

namespace {

// Step 2: the ROI, the router and culling (fills roi, exact_path, kept_*, cull_*, candidate).
void trace_roi(Explanation& e, const PairResult& pr, const Object& oa, const Object& ob, const DetectOptions& opt,
               const IdMap& map_a, const IdMap& map_b, std::vector<std::uint32_t>& kept_a,
               std::vector<std::uint32_t>& kept_b) {
  const Mesh& ma = oa.mesh;
  const Mesh& mb = ob.mesh;
  const PairQuery& q = e.query;
  e.roi = true;
  e.exact_path = pr.exact_stage;
  e.predicted_exact_ms = pr.predicted_exact_ms;
  e.predicted_image_ms = pr.predicted_image_ms;
  for (const Contact& c : pr.colliding)
    if (c.tri_a == q.tri_a && c.tri_b == q.tri_b) e.reported = true;
  const auto why = [&](const Mesh& m, std::uint32_t t, const std::string& other) -> std::string {
    if (!triangle_touches(m, t, pr.roi)) return "its box does not touch the ROI (the overlap of the two objects' boxes)";
    return "contact culling: its box touches no grid cell that a triangle of '" + other +
           "' touches (peelcd/core/image/cull.h)";
  };
  if (opt.cull == Cull::contact) {
    ContactCull cull;  // as the detector culled it: one round for the exact CPU path, all for the image stage
    cull_to_contact_region(ma, mb, pr.roi, cull, pr.exact_stage ? 1 : kMaxCullRounds);
    kept_a = cull.kept_a;
    kept_b = cull.kept_b;
    e.kept_a = std::binary_search(kept_a.begin(), kept_a.end(), q.tri_a);
    e.kept_b = std::binary_search(kept_b.begin(), kept_b.end(), q.tri_b);
  } else {  // Cull::box: what touches the ROI (the views pad it further)
    e.kept_a = triangle_touches(ma, q.tri_a, pr.roi);
    e.kept_b = triangle_touches(mb, q.tri_b, pr.roi);
  }
  if (!e.kept_a) e.cull_a = why(ma, q.tri_a, ob.name);
  if (!e.kept_b) e.cull_b = why(mb, q.tri_b, oa.name);
  if (e.exact_path) {
    e.candidate = e.kept_a && e.kept_b && triangle_bounds(ma, q.tri_a).overlaps(triangle_bounds(mb, q.tri_b));
  } else {
    std::vector<std::uint64_t> candidates;
    expand_pcs(pr.pcs, map_a, map_b, candidates);
    e.candidate = std::binary_search(candidates.begin(), candidates.end(), pack_pair(q.tri_a, q.tri_b));
  }
}

// Step 4: the verdict from the exact answer, the ROI and the views.
void trace_verdict(Explanation& e, bool has_roi) {
  const ViewReport* found_in = nullptr;
  for (const ViewReport& v : e.views)
    if (!found_in && v.reason == Verdict::found) found_in = &v;
  if (e.adjacent) {
    e.verdict = Verdict::no_contact;
    e.verdict_line = "no contact: the two triangles share a vertex (adjacent triangles of one object are never a self "
                     "pair, docs/design.md)";
  } else if (!e.intersect) {
    if (has_roi && (!e.kept_a || !e.kept_b)) {
      e.verdict = Verdict::culled;
      e.verdict_line = "no contact: the triangles do not intersect; culled before drawing (" +
                       std::string(!e.kept_a ? "A: " + e.cull_a : "B: " + e.cull_b) + ")";
    } else {
      e.verdict = Verdict::no_contact;
      e.verdict_line = std::string("no contact: the triangles do not intersect") +
                       (!has_roi ? " (the objects' boxes do not overlap)"
                                 : e.candidate ? " (a candidate; the exact test rejected it)" : " (not a candidate)");
    }
  } else if (!has_roi) {
    e.verdict = Verdict::no_roi;
    e.verdict_line = "missed: the objects' boxes do not overlap (impossible for an intersecting pair: a bug)";
  } else if (e.reported && e.exact_path) {
    e.verdict = Verdict::found_exact;
    e.verdict_line = "found by the exact CPU path (the router predicted " + g(e.predicted_exact_ms) + " ms against " +
                     g(e.predicted_image_ms) + " ms for the image stage)";
  } else if (e.reported) {
    e.verdict = Verdict::found;
    e.verdict_line = found_in ? "found in view " + std::to_string(found_in->view) +
                                    (found_in->found_texels ? " at texel (" + std::to_string(found_in->found_x) + ", " +
                                                                  std::to_string(found_in->found_y) + ")"
                                                            : std::string())
                              : "found (through a view resolved by box tests)";
  } else if (!e.kept_a || !e.kept_b) {
    e.verdict = Verdict::culled;
    e.verdict_line = "missed: culled (" + std::string(!e.kept_a ? "A: " + e.cull_a : "B: " + e.cull_b) +
                     "); culling is meant to keep every colliding pair: a bug";
  } else if (e.candidate) {
    e.verdict = Verdict::not_located;
    e.verdict_line = "missed: a candidate that the narrow phase rejected (a bug)";
  } else if (e.views.empty()) {
    e.verdict = Verdict::not_located;
    e.verdict_line = "missed: no view was peeled for this ROI";
  } else {
    const ViewReport& first = e.views.front();
    bool all_short = true;
    double longest = 0.0;
    for (const ViewReport& v : e.views) {
      all_short = all_short && v.segment_texels < 1.0;
      longest = std::max(longest, v.segment_texels);
    }
    e.verdict = first.reason;
    if (all_short && (first.reason == Verdict::sub_texel || first.reason == Verdict::not_located)) {
      e.verdict = Verdict::sub_texel;
      e.verdict_line = "missed: tile too coarse: the segment projects to under one texel in every view (at most " +
                       g(longest) + " texels); view " + std::to_string(first.view) + ": " + first.summary;
    } else {
      e.verdict_line = std::string("missed: ") + verdict_text(first.reason) + ": view " + std::to_string(first.view) + ": " +
                       first.summary;
    }
  }
}

}  // namespace

using detail::trace_view;

Explanation FrameTrace::explain(const PairQuery& query) const {
  Explanation e;
  PairQuery q = query;
  if (q.object_a >= objects_.size() || q.object_b >= objects_.size())
    throw std::invalid_argument("peelcd::oracle::FrameTrace::explain(): bad object indices");
  const bool self = q.object_a == q.object_b;
  if (self && !(options_.self || objects_[q.object_a].self))
    throw std::invalid_argument("peelcd explain: both triangles are of '" + objects_[q.object_a].name +
                                "', which does not ask for self-collision (--self, or \"self\": true on the object)");
  if (self && q.tri_a > q.tri_b) std::swap(q.tri_a, q.tri_b);
  if (q.object_a > q.object_b) {
    std::swap(q.object_a, q.object_b);
    std::swap(q.tri_a, q.tri_b);
  }
  const Object& oa = objects_[q.object_a];
  const Object& ob = objects_[q.object_b];
  const Mesh& ma = oa.mesh;
  const Mesh& mb = ob.mesh;
  if (q.tri_a >= ma.triangles.size() || q.tri_b >= mb.triangles.size())
    throw std::invalid_argument("peelcd::oracle::FrameTrace::explain(): triangle index out of range");
  const DetectOptions& opt = options_;
  e.query = q;
  e.name_a = oa.name;
  e.name_b = ob.name;
  e.options = options_to_json(opt);
  e.backend = backend_;
  e.renderer = renderer_;

  // 1. The exact answer (a self couple that shares a vertex is never a pair: docs/design.md).
  const TriangleCorners ca = corners(ma, q.tri_a), cb = corners(mb, q.tri_b);
  std::vector<std::uint32_t> rep;
  if (self) vertex_representatives(ma, opt.self_adjacency, rep);
  e.adjacent = self && triangles_adjacent(ma, rep, q.tri_a, q.tri_b);
  e.intersect = !e.adjacent && triangles_intersect(ca, cb);
  if (e.intersect) {
    e.kind = to_string(classify_contact(ca, cb));
    std::tie(e.p, e.q) = intersection_segment(ca, cb);
  }

  // 2. The ROI, the router and culling.
  const PairResult* pr = nullptr;
  std::size_t pair_index = 0;
  for (std::size_t i = 0; i < result_.pairs.size(); ++i)
    if (result_.pairs[i].object_a == q.object_a && result_.pairs[i].object_b == q.object_b) pr = &result_.pairs[i], pair_index = i;
  const IdMap map_a(ma, opt.ids), map_b(mb, opt.ids);
  e.id_a = corner_id(ma, q.tri_a, 2, opt.ids);
  e.id_b = corner_id(mb, q.tri_b, 2, opt.ids);
  const std::set<std::uint32_t> stand_a = ids_standing_for(ma, map_a, q.tri_a);
  const std::set<std::uint32_t> stand_b = ids_standing_for(mb, map_b, q.tri_b);
  std::vector<std::uint32_t> kept_a, kept_b;
  if (pr) trace_roi(e, *pr, oa, ob, opt, map_a, map_b, kept_a, kept_b);

  // 3. The views.
  if (pr && !e.exact_path)
    for (const CapturedView& cv : captured_)
      if (cv.pair == pair_index)
        e.views.push_back(trace_view(e, cv, oa, ob, opt, kept_a, kept_b, stand_a, stand_b, ca, cb));

  // 4. The verdict; containment (the objects collide with no triangle pair: docs/design.md).
  trace_verdict(e, pr != nullptr);
  if (pr && opt.depth && pr->object_a != pr->object_b) {
    e.depth_asked = true;
    e.depth = pr->depth;
  }
  if (pr && (pr->relation == Relation::a_inside_b || pr->relation == Relation::b_inside_a)) {
    const bool a_in = pr->relation == Relation::a_inside_b;
    e.verdict_line += "; the objects collide without contact: '" + (a_in ? e.name_a : e.name_b) + "' is inside '" +
                      (a_in ? e.name_b : e.name_a) +
                      "' (one vertex of each of its pieces tested against the other, a closed mesh, exactly)";
  } else if (pr && pr->relation == Relation::unknown && !pr->relation_note.empty()) {
    e.verdict_line += "; whether one object is inside the other is unknown: " + pr->relation_note;
  }
  return e;
}

}  // namespace peelcd::oracle
