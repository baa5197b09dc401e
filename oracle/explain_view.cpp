// One captured view of explain's trace (explain_view.h).
#include "explain_view.h"

#include "explain_words.h"

#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/image/kbuffer.h"
#include "peelcd/core/exact/narrow_phase.h"
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

namespace peelcd::oracle::detail {
namespace {

using texel::as_float;

using words::g;
using words::object_word;

// Window position (texels; texel i spans [i, i + 1)) of world point p in `view`.
std::array<double, 2> window_of(const RoiView& view, const Vec3& p) {
  const Vec3 local = p - view.center;
  const double n = view.resolution;
  return {(local.dot(view.frame.u) / view.half_uv + 1.0) * 0.5 * n, (local.dot(view.frame.v) / view.half_uv + 1.0) * 0.5 * n};
}

// What the trace of one view knows: the view as captured, the IDs standing for the two
// triangles, and where each triangle alone lands (the CPU stage's model: depth per texel, NaN
// where it covers no texel centre).
struct ViewContext {
  const CapturedView& cv;
  const RoiView& view;
  const DetectOptions& opt;
  const std::set<std::uint32_t>& stand_a;
  const std::set<std::uint32_t>& stand_b;
  int n = 0;
  bool conservative = false;
  float epsilon_window = 0, slope = 0;
  std::vector<float> za, zb;
};

// Where each triangle alone lands in the view: the CPU stage's model with just the two triangles.
void model_depths(ViewContext& c, const Object& oa, const Object& ob, std::uint32_t tri_a, std::uint32_t tri_b) {
  const std::vector<std::uint32_t> only_a = {tri_a}, only_b = {tri_b};
  PeelJob job;
  job.objects[0] = &oa;
  job.objects[1] = &ob;
  job.triangles[0] = &only_a;
  job.triangles[1] = &only_b;
  job.view = c.view;
  job.ids = IdMode::unique;
  job.peel = PeelMode::full;
  job.epsilon = 0.0;
  job.capture = true;
  job.conservative = c.opt.conservative;
  PeelResult alone;
  Timings ignored;
  CpuImageStage model;
  model.peel(job, alone, ignored);
  const std::size_t texels = std::size_t(c.n) * std::size_t(c.n);
  c.za.assign(texels, NAN);
  c.zb.assign(texels, NAN);
  for (const auto& layer : alone.captured)
    for (std::size_t t = 0; t < texels; ++t) {
      if (texel_empty(layer, t)) continue;
      (texel_object(layer, t) == 0 ? c.za : c.zb)[t] = as_float(layer[4 * t]);
    }
}

// Why the stage's layers at texel t did not report the pair: a missing layer of A or B, and what
// alternate peeling took in its place.
void explain_missing_layer(const ViewContext& c, TexelReport& r) {
  const bool miss_a = !std::any_of(r.layers.begin(), r.layers.end(), [](const TexelLayer& l) { return l.stands_a; });
  const float want = miss_a ? r.model_depth_a : r.model_depth_b;
  const std::uint32_t object = miss_a ? 0u : 1u;
  const TexelLayer* hider = nullptr;
  for (const TexelLayer& l : r.layers)
    if (l.object == object && !(l.depth > want)) hider = &l;
  if (c.opt.peel == PeelMode::alternate && hider) {
    r.status = Verdict::separated;
    r.note = std::string(miss_a ? "A" : "B") + "'s triangle (depth " + g(want) + ") was not peeled here: layer " +
             std::to_string(hider->layer) + " holds " + object_word(object) + " ID " + std::to_string(hider->id) +
             " at depth " + g(hider->depth) + ", and alternate peeling takes the next layer from the other object";
    for (const TexelLayer& l : r.layers)
      if (l.layer > hider->layer && l.object != object) {
        if (want < l.depth)
          r.note += "; " + object_word(object) + "'s next turn looks only behind layer " + std::to_string(l.layer) +
                    " (" + object_word(l.object) + " at depth " + g(l.depth) + "), and this fragment lies in front of it";
        break;
      }
  } else if (c.opt.peel == PeelMode::alternate && !r.layers.empty() && r.layers.front().object != object &&
             want < r.layers.front().depth) {
    r.status = Verdict::separated;
    r.note = std::string(miss_a ? "A" : "B") + "'s triangle (depth " + g(want) + ") lies in front of layer 0 (" +
             object_word(r.layers.front().object) + " at depth " + g(r.layers.front().depth) +
             "): alternate peeling began with the other object and never comes back to it";
  } else {
    r.status = Verdict::not_located;
    r.note = std::string(miss_a ? "A" : "B") + "'s triangle covers the texel in the model but is in no layer of the stage here";
  }
}

// The stage's layers at texel t, with the tests between layers standing for the two triangles
// (the same float operations as the stage's: peelcd/core/image/pcs_test.inc), and the texel's verdict.
TexelReport analyse_texel(const ViewContext& c, std::size_t t) {
  const std::size_t n = std::size_t(c.n);
  TexelReport r;
  r.x = int(t % n);
  r.y = int(t / n);
  r.model_a = !std::isnan(c.za[t]);
  r.model_b = !std::isnan(c.zb[t]);
  r.model_depth_a = c.za[t];
  r.model_depth_b = c.zb[t];
  for (std::size_t k = 0; k < c.cv.layers.size(); ++k) {
    const auto& layer = c.cv.layers[k];
    if (texel_empty(layer, t)) continue;
    TexelLayer l;
    l.layer = int(k);
    l.object = texel_object(layer, t);
    l.id = texel_id1(layer, t) - 1u;
    l.depth = as_float(layer[4 * t]);
    l.depth_hi = c.conservative ? texel::value(layer, t, texel::kUpper) : l.depth;
    l.stands_a = l.object == 0 && c.stand_a.count(l.id);
    l.stands_b = l.object == 1 && c.stand_b.count(l.id);
    r.layers.push_back(l);
  }
  for (std::size_t i = 0; i < r.layers.size(); ++i)
    for (std::size_t j = i + 1; j < r.layers.size(); ++j) {
      const TexelLayer& x = r.layers[i];
      const TexelLayer& y = r.layers[j];
      if (!((x.stands_a && y.stands_b) || (x.stands_b && y.stands_a))) continue;
      TexelTest test;
      test.layer_a = x.stands_a ? x.layer : y.layer;
      test.layer_b = x.stands_a ? y.layer : x.layer;
      if (c.conservative) {  // resolve_intervals: j sorts after i; overlap unless lo_j > hi_i
        test.value = y.depth - x.depth_hi;
        test.bound = 0.0f;
        test.pass = pcs_intervals_overlap(x.depth, x.depth_hi, y.depth, y.depth_hi);
      } else {  // kbuffer.cpp's test_pair on adjacent layers, in the same float operations
        const auto& lx = c.cv.layers[std::size_t(x.layer)];
        const auto& ly = c.cv.layers[std::size_t(y.layer)];
        test.adjacent = y.layer == x.layer + 1;
        const float z0 = texel::value(lx, t, texel::kDepth), z1 = texel::value(ly, t, texel::kDepth);
        test.value = std::fabs(z1 - z0);
        const float spread = std::fabs(texel::value(ly, t, texel::kDzdx) - texel::value(lx, t, texel::kDzdx)) +
                             std::fabs(texel::value(ly, t, texel::kDzdy) - texel::value(lx, t, texel::kDzdy));
        test.bound = c.epsilon_window + c.slope * spread;  // for the report; the test itself:
        test.pass = test.adjacent && pcs_within_epsilon(z0, z1, spread, c.epsilon_window, c.slope);
      }
      r.tests.push_back(test);
    }
  const bool has_a = std::any_of(r.layers.begin(), r.layers.end(), [](const TexelLayer& l) { return l.stands_a; });
  const bool has_b = std::any_of(r.layers.begin(), r.layers.end(), [](const TexelLayer& l) { return l.stands_b; });
  const TexelTest* best = nullptr;  // the passing test, or the adjacent one closest to passing
  for (const TexelTest& test : r.tests)
    if (test.pass) best = &test;
  if (!best)
    for (const TexelTest& test : r.tests)
      if (test.adjacent && (!best || test.value - test.bound < best->value - best->bound)) best = &test;
  const double to_world = 2.0 * c.view.half_depth;
  if (best && best->pass) {
    r.status = Verdict::found;
    r.note = "PCS: layers " + std::to_string(best->layer_a) + " (A) and " + std::to_string(best->layer_b) + " (B), " +
             (c.conservative ? "intervals overlap" : "|dz| " + g(best->value) + " < " + g(best->bound));
  } else if (!(r.model_a && r.model_b)) {
    r.status = Verdict::sub_texel;
    r.note = std::string("not covered by both triangles (model: ") + (r.model_a ? "A" : "") + (r.model_b ? "B" : "") +
             (r.model_a || r.model_b ? " only)" : "neither)");
  } else if (best) {
    r.status = Verdict::above_epsilon;
    r.note = c.conservative ? "intervals apart by " + g(best->value) + " (window depth)"
                            : "|dz| " + g(best->value) + " >= threshold " + g(best->bound) + ": above by " +
                                  g(best->value - best->bound) + " window = " + g((best->value - best->bound) * to_world) +
                                  " world";
  } else if (has_a && has_b) {
    r.status = Verdict::separated;
    const TexelTest& t0 = r.tests.front();
    r.note = "layers " + std::to_string(t0.layer_a) + " (A) and " + std::to_string(t0.layer_b) +
             " (B) are not adjacent: a layer between them is tested instead";
  } else {
    explain_missing_layer(c, r);
  }
  return r;
}

// The texels examined in detail: the segment's (sampled every 1/16 texel) first, then other
// texels both triangles cover, up to 48. Sets v.segment_texel_count.
std::vector<std::size_t> chosen_texels(const ViewContext& c, ViewReport& v, bool intersect,
                                       const std::vector<std::size_t>& common) {
  const int n = c.n;
  std::vector<std::size_t> chosen;
  std::set<std::size_t> seen;
  if (intersect) {
    const int steps = int(std::min(65536.0, std::ceil(v.segment_texels * 16.0))) + 1;
    for (int s = 0; s <= steps; ++s) {
      const double f = steps ? double(s) / steps : 0.0;
      const double x = v.segment[0][0] + f * (v.segment[1][0] - v.segment[0][0]);
      const double y = v.segment[0][1] + f * (v.segment[1][1] - v.segment[0][1]);
      const int ix = int(std::floor(x)), iy = int(std::floor(y));
      if (ix < 0 || iy < 0 || ix >= n || iy >= n) continue;
      const std::size_t t = std::size_t(iy) * std::size_t(n) + std::size_t(ix);
      if (seen.insert(t).second) chosen.push_back(t);
    }
  }
  v.segment_texel_count = chosen.size();
  constexpr std::size_t kDetailed = 48;
  for (const std::size_t t : common)
    if (chosen.size() < kDetailed && seen.insert(t).second) chosen.push_back(t);
  return chosen;
}

// The view's reason and summary from its counts and its detailed texels.
void summarise_view(const ViewContext& c, ViewReport& v) {
  // The reason among the common texels (the detailed ones): the one closest to being found,
  // the segment's texels before the others, then above epsilon before separated before
  // unexplained, then the smallest excess.
  Verdict best = Verdict::no_contact;
  double best_excess = std::numeric_limits<double>::infinity();
  bool best_on_segment = false;
  const auto rank = [](Verdict x) { return x == Verdict::above_epsilon ? 0 : x == Verdict::separated ? 1 : 2; };
  std::size_t counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < v.texels.size(); ++i) {
    const TexelReport& r = v.texels[i];
    if (!r.model_a || !r.model_b || r.status == Verdict::found) continue;
    ++counts[rank(r.status)];
    double excess = std::numeric_limits<double>::infinity();
    for (const TexelTest& test : r.tests)
      if (test.adjacent) excess = std::min(excess, double(test.value - test.bound));
    const bool on_segment = i < v.segment_texel_count;
    if (best == Verdict::no_contact || (on_segment && !best_on_segment) ||
        (on_segment == best_on_segment &&
         (rank(r.status) < rank(best) ||
          (r.status == Verdict::above_epsilon && best == Verdict::above_epsilon && excess < best_excess)))) {
      best = r.status;
      best_excess = excess;
      best_on_segment = on_segment;
    }
  }
  const std::string tally = " (common texels examined: " + std::to_string(counts[0]) + " above the threshold, " +
                            std::to_string(counts[1]) + " separated, " + std::to_string(counts[2]) + " unexplained)";
  for (std::size_t i = 0; i < v.segment_texel_count && i < v.texels.size(); ++i)
    if (v.texels[i].status == Verdict::found) {  // name a texel on the segment when one reports it
      v.found_x = v.texels[i].x, v.found_y = v.texels[i].y;
      break;
    }

  const auto extent = [](const std::array<std::array<double, 2>, 3>& w) {
    double x0 = w[0][0], x1 = x0, y0 = w[0][1], y1 = y0;
    for (const auto& p : w) x0 = std::min(x0, p[0]), x1 = std::max(x1, p[0]), y0 = std::min(y0, p[1]), y1 = std::max(y1, p[1]);
    return std::max(x1 - x0, y1 - y0);
  };
  const auto no_fragment = [&](const char* who, const std::array<std::array<double, 2>, 3>& w) {
    const double ext = extent(w);
    if (ext < 1.0) {
      v.reason = Verdict::sub_texel;
      v.summary = std::string(who) + "'s triangle projects to " + g(ext) + " texels: it covers no texel centre";
    } else {
      v.reason = Verdict::edge_on;
      const double area = std::fabs((w[1][0] - w[0][0]) * (w[2][1] - w[0][1]) - (w[2][0] - w[0][0]) * (w[1][1] - w[0][1])) * 0.5;
      v.summary = std::string(who) + "'s triangle is drawn but has no fragment: seen edge-on (" + g(ext) + " texels long, " +
                  g(area) + " texels^2 of area)";
    }
  };
  const DetectOptions& opt = c.opt;
  if (v.pcs_found) {
    v.reason = Verdict::found;
    v.summary = v.found_texels ? "found at texel (" + std::to_string(v.found_x) + ", " + std::to_string(v.found_y) + "), " +
                                     std::to_string(v.found_texels) + " texel(s) report it"
                               : "found in the view's PCS (texel not located: a shared-ID neighbour)";
  } else if (!v.drawn_a || !v.drawn_b) {
    v.reason = Verdict::culled;
    v.summary = std::string(!v.drawn_a ? "A" : "B") + "'s triangle is not drawn: its box misses the view's padded ROI" +
                (opt.cull == Cull::contact ? " or culling dropped it" : "");
  } else if (v.exhaustive) {
    v.reason = Verdict::not_located;
    v.summary = "no layers: the view was resolved by box tests (k-buffer too deep)";
  } else if (v.fragments_a == 0) {
    no_fragment("A", v.window_a);
  } else if (v.fragments_b == 0) {
    no_fragment("B", v.window_b);
  } else if (v.common_texels == 0) {
    v.reason = Verdict::sub_texel;
    v.summary = "no texel centre is covered by both triangles (the segment projects to " + g(v.segment_texels) + " texels)";
  } else {
    v.reason = best == Verdict::no_contact ? Verdict::not_located : best;
    const std::string where = best_on_segment ? "where the segment crosses" : "at the common texels";
    if (v.reason == Verdict::above_epsilon)
      v.summary = v.conservative ? "intervals apart at every common texel"
                                 : std::string(best_on_segment ? "where the segment crosses" : "at a common texel") +
                                       ", adjacent layers, depth difference above the threshold by " + g(best_excess) +
                                       " window depth = " + g(best_excess * 2.0 * c.view.half_depth) + " world (epsilon " +
                                       g(c.view.window_to_world_depth(v.epsilon_window)) + ")";
    else if (v.reason == Verdict::separated)
      v.summary = opt.peel == PeelMode::alternate
                      ? where + ", alternate peeling skipped one of the two: a layer of the same object was taken "
                                "instead, or the surface lay in front of the other object's first layer"
                      : where + ", another layer lies between the two (only adjacent layers are tested)";
    else
      v.summary = "both cover " + std::to_string(v.common_texels) + " texel(s) but no test involving them was found";
    v.summary += tally;
  }
}

// The crop for the page: the chosen texels (or the triangles' common ones) and a margin.
void crop_view(const ViewContext& c, ViewReport& v, const std::vector<std::size_t>& chosen,
               const std::vector<bool>& found_at) {
  const int n = c.n;
  int x0 = n, y0 = n, x1 = -1, y1 = -1;
  const auto grow = [&](int x, int y) { x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y); };
  for (std::size_t i = 0; i < chosen.size(); ++i) grow(int(chosen[i] % std::size_t(n)), int(chosen[i] / std::size_t(n)));
  if (x1 < 0) grow(std::clamp(int(v.window_a[0][0]), 0, n - 1), std::clamp(int(v.window_a[0][1]), 0, n - 1));
  const int margin = 6, side = std::max({16, x1 - x0 + 1 + 2 * margin, y1 - y0 + 1 + 2 * margin});
  const int w = std::min(n, std::min(side, 96));
  v.crop_w = v.crop_h = w;
  v.crop_x = std::clamp((x0 + x1) / 2 - w / 2, 0, n - w);
  v.crop_y = std::clamp((y0 + y1) / 2 - w / 2, 0, n - w);
  v.crop_flags.assign(std::size_t(w) * w, 0);
  v.crop_depth.assign(std::size_t(w) * w, NAN);
  for (int y = 0; y < w; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t t = std::size_t(v.crop_y + y) * std::size_t(n) + std::size_t(v.crop_x + x);
      std::uint8_t f = 0;
      if (!std::isnan(c.za[t])) f |= 1;
      if (!std::isnan(c.zb[t])) f |= 2;
      if (!c.cv.layers.empty()) {
        if (!texel_empty(c.cv.layers[0], t)) v.crop_depth[std::size_t(y) * w + x] = as_float(c.cv.layers[0][4 * t]);
        if (found_at[t]) f |= 4;
      }
      v.crop_flags[std::size_t(y) * w + x] = f;
    }
}

}  // namespace

// Step 3: one captured view of the pair's ROI.
ViewReport trace_view(const Explanation& e, const CapturedView& cv, const Object& oa, const Object& ob,
                      const DetectOptions& opt, const std::vector<std::uint32_t>& kept_a,
                      const std::vector<std::uint32_t>& kept_b, const std::set<std::uint32_t>& stand_a,
                      const std::set<std::uint32_t>& stand_b, const TriangleCorners& ca, const TriangleCorners& cb) {
  const PairQuery& q = e.query;
  ViewReport v;
  ViewContext c{cv, cv.roi, opt, stand_a, stand_b, 0, false, 0, 0, {}, {}};
  const RoiView& view = cv.roi;
  const int n = c.n = view.resolution;
  v.view = cv.view;
  v.resolution = n;
  v.texel = view.texel();
  v.epsilon_window = c.epsilon_window = cv.epsilon_window;
  v.slope = c.slope = cv.slope;
  v.conservative = c.conservative = opt.conservative;
  std::vector<std::uint32_t> in_view;
  triangles_in_view(oa.mesh, view, opt.cull == Cull::contact ? &kept_a : nullptr, in_view);
  v.drawn_a = std::binary_search(in_view.begin(), in_view.end(), q.tri_a);
  triangles_in_view(ob.mesh, view, opt.cull == Cull::contact ? &kept_b : nullptr, in_view);
  v.drawn_b = std::binary_search(in_view.begin(), in_view.end(), q.tri_b);
  v.exhaustive = cv.layers.empty();
  for (int k = 0; k < 3; ++k) {
    v.window_a[k] = window_of(view, ca[k]);
    v.window_b[k] = window_of(view, cb[k]);
  }
  if (e.intersect) {
    v.segment[0] = window_of(view, e.p);
    v.segment[1] = window_of(view, e.q);
    v.segment_texels = std::hypot(v.segment[1][0] - v.segment[0][0], v.segment[1][1] - v.segment[0][1]);
  }
  for (const IdPair& p : cv.pcs)
    if (stand_a.count(p.a) && stand_b.count(p.b)) v.pcs_found = true;

  model_depths(c, oa, ob, q.tri_a, q.tri_b);
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  std::vector<std::size_t> common;
  for (std::size_t t = 0; t < texels; ++t) {
    v.fragments_a += !std::isnan(c.za[t]);
    v.fragments_b += !std::isnan(c.zb[t]);
    if (!std::isnan(c.za[t]) && !std::isnan(c.zb[t])) common.push_back(t);
  }
  v.common_texels = common.size();
  const std::vector<std::size_t> chosen = chosen_texels(c, v, e.intersect, common);

  // Every texel once: where the pair's test passed (the count, the page's marks); with unique
  // IDs only texels either triangle covers can hold its ID, with shared IDs any texel may.
  std::vector<bool> found_at(texels, false);
  for (std::size_t t = 0; t < texels && !cv.layers.empty(); ++t) {
    if (opt.ids == IdMode::unique && std::isnan(c.za[t]) && std::isnan(c.zb[t])) continue;
    if (analyse_texel(c, t).status != Verdict::found) continue;
    found_at[t] = true;
    if (v.found_texels++ == 0) v.found_x = int(t % std::size_t(n)), v.found_y = int(t / std::size_t(n));
  }
  // The chosen texels in detail, analysed once.
  if (!cv.layers.empty())
    for (const std::size_t t : chosen) v.texels.push_back(analyse_texel(c, t));
  summarise_view(c, v);
  crop_view(c, v, chosen, found_at);
  return v;
}

}  // namespace peelcd::oracle::detail
