// Comparing two dumps (peelcd/oracle/compare.h): named comparators for the header, a pair's
// contacts, a view's record and its layers, each texel judged by the tier's rule.
#include "peelcd/oracle/compare.h"
#include "peelcd/oracle/images.h"
#include "peelcd/oracle/viewer.h"
#include "text_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <sstream>

namespace fs = std::filesystem;

namespace peelcd::oracle {
namespace {

using texel::as_float;

std::string hex(std::uint32_t w) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", w);
  return buf;
}

// |a - b| of two float words.
double depth_distance(std::uint32_t a, std::uint32_t b) { return std::fabs(double(as_float(a)) - double(as_float(b))); }

bool close_relative(float a, float b, double relative) {
  return std::fabs(double(a) - double(b)) <= relative * std::max(std::fabs(double(a)), std::fabs(double(b)));
}

// Is texel (x, y) of `layer` within `r` texels of a texel with a different ID / object / emptiness?
bool near_edge(const std::vector<std::uint32_t>& layer, int n, int x, int y, int r) {
  const std::uint32_t w = layer[4 * (std::size_t(y) * n + x) + 1];
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx < 0 || yy < 0 || xx >= n || yy >= n) continue;
      if (layer[4 * (std::size_t(yy) * n + xx) + 1] != w) return true;
    }
  return false;
}

// The first layer at texel t that takes part in a tie: layers k-1 and k of different objects
// at one depth (within `tolerance`); `none` if there is none. Another rasterizer's rounding may
// order the two the other way, keep both or peel past one, so from layer k-1 on the texel may
// differ (the two are within epsilon of each other: both sides' PCS test pairs them).
std::size_t first_tie_layer(const std::vector<std::vector<std::uint32_t>>& layers, std::size_t t, double tolerance,
                            std::size_t none) {
  for (std::size_t k = 1; k < layers.size(); ++k) {
    const auto &l0 = layers[k - 1], &l1 = layers[k];
    if (!texel_empty(l0, t) && !texel_empty(l1, t) && texel_object(l0, t) != texel_object(l1, t) &&
        depth_distance(l0[4 * t], l1[4 * t]) <= tolerance)
      return k - 1;
  }
  return none;
}

// Point sampling: the first layer at texel t from which one side's layers are the other's with
// one fragment more, that fragment a twin of a neighbour in its own sequence: the same ID word (a
// sliver triangle inside one shared ID's region that one rasterizer sampled and the other did
// not) or the same object at the same depth (an edge of two triangles of one object through the
// texel centre, which the fill rules give to one or both); every later layer matching by ID word
// and depth within `tolerance`. `none` if the texel is not such a shift. The colliding pairs are
// checked on their own (a lossy configuration's misses against the exact reference).
std::size_t first_sliver_shift(const std::vector<std::vector<std::uint32_t>>& e,
                               const std::vector<std::vector<std::uint32_t>>& a, std::size_t t, double tolerance,
                               std::size_t none) {
  const auto depth = [&](const std::vector<std::vector<std::uint32_t>>& l, std::size_t k) { return l[k][4 * t]; };
  const auto word = [&](const std::vector<std::vector<std::uint32_t>>& l, std::size_t k) {
    return k < l.size() ? texel::word(l[k], t, texel::kKey) : 0u;
  };
  const auto count = [&](const std::vector<std::vector<std::uint32_t>>& l) {
    std::size_t c = 0;
    while (c < l.size() && word(l, c) != 0u) ++c;
    return c;
  };
  const std::size_t ne = count(e), na = count(a);
  if (ne != na + 1 && na != ne + 1) return none;
  const auto& longer = ne > na ? e : a;
  const auto& shorter = ne > na ? a : e;
  const std::size_t n_short = std::min(ne, na);
  std::size_t i = 0;  // the first layer where the two differ by ID word or depth
  while (i < n_short && word(longer, i) == word(shorter, i) &&
         depth_distance(depth(longer, i), depth(shorter, i)) <= tolerance)
    ++i;
  // The extra fragment i must share its ID word with a neighbour in its own sequence, or lie at
  // the neighbour's depth on the same object (a texel centre on an edge two triangles of one
  // object share: one fill rule samples both, the other one).
  const auto twin = [&](std::size_t j) {
    if (j >= longer.size() || word(longer, j) == 0u) return false;
    if (word(longer, j) == word(longer, i)) return true;
    return (word(longer, j) >> 31) == (word(longer, i) >> 31) &&
           depth_distance(depth(longer, j), depth(longer, i)) <= tolerance;
  };
  if (!((i > 0 && twin(i - 1)) || twin(i + 1))) return none;
  for (std::size_t k = i; k < n_short; ++k)
    if (word(longer, k + 1) != word(shorter, k) || depth_distance(depth(longer, k + 1), depth(shorter, k)) > tolerance)
      return none;
  return i;
}

// With shared IDs: is `z` within the golden depths of the texels around (x, y) that hold the same
// ID word (another triangle of the same ID, one texel off)?
bool within_neighbour_depths(const std::vector<std::uint32_t>& layer, int n, int x, int y, float z, double tolerance) {
  const std::uint32_t w = layer[4 * (std::size_t(y) * n + x) + 1];
  double lo = INFINITY, hi = -INFINITY;
  for (int dy = -kIdSilhouetteTexels; dy <= kIdSilhouetteTexels; ++dy)
    for (int dx = -kIdSilhouetteTexels; dx <= kIdSilhouetteTexels; ++dx) {
      const int xx = x + dx, yy = y + dy;
      if (xx < 0 || yy < 0 || xx >= n || yy >= n) continue;
      const std::size_t t = std::size_t(yy) * n + xx;
      if (texel::word(layer, t, texel::kKey) != w) continue;
      lo = std::min(lo, double(as_float(layer[4 * t])));
      hi = std::max(hi, double(as_float(layer[4 * t])));
    }
  return z >= lo - tolerance && z <= hi + tolerance;
}

}  // namespace

const char* to_string(Tier tier) { return tier == Tier::exact ? "exact" : "hardware"; }

std::size_t hardware_miss_slack(std::size_t reference_pairs) {
  return kMissSlackPairs + std::size_t(std::ceil(kMissSlackFraction * double(reference_pairs)));
}

namespace {

using Pairs = std::vector<std::array<std::uint32_t, 2>>;

std::string list_pairs(const Pairs& v) {
  std::string s;
  for (std::size_t k = 0; k < v.size() && k < 8; ++k) s += " (" + std::to_string(v[k][0]) + "," + std::to_string(v[k][1]) + ")";
  if (v.size() > 8) s += " ...";
  return s;
}

// What both dumps record: the shader hash and renderer (notes), the options both record (an
// older writer may record fewer) and the ROI count.
bool compare_header(const Dump& e, const Dump& a, Comparison& c) {
  if (e.shader_hash != a.shader_hash)
    c.notes.push_back("shader sources changed since the golden was recorded (hash " + e.shader_hash + ", now " +
                      a.shader_hash + ")");
  if (e.renderer != a.renderer) c.notes.push_back("renderer: golden \"" + e.renderer + "\", now \"" + a.renderer + "\"");
  for (const auto& [key, value] : e.options.items())
    if (a.options.contains(key) && a.options[key] != value)
      c.failures.push_back("option \"" + key + "\" differs: golden " + value.dump() + ", now " + a.options[key].dump());
  if (e.pairs.size() == a.pairs.size()) return true;
  c.failures.push_back("ROI count differs: golden " + std::to_string(e.pairs.size()) + ", now " +
                       std::to_string(a.pairs.size()));
  return false;
}

// A pair's colliding pairs. The exact tier wants the same list. The hardware tier wants the same
// list in the conservative mode (it must find every contact whatever the rasterizer) and, in a
// lossy configuration, no more misses against the exact reference than the golden's plus
// hardware_miss_slack(); extra pairs are exactly verified contacts, listed as notes. Then the
// pair's PCS (the exact tier only fails on it).
void compare_pair_contacts(const DumpPair& pe, const DumpPair& pa, Tier tier, bool conservative, Comparison& c) {
  Pairs missing, extra;
  std::set_difference(pe.colliding.begin(), pe.colliding.end(), pa.colliding.begin(), pa.colliding.end(),
                      std::back_inserter(missing));
  std::set_difference(pa.colliding.begin(), pa.colliding.end(), pe.colliding.begin(), pe.colliding.end(),
                      std::back_inserter(extra));
  if (pe.has_reference && pa.has_reference && pe.reference != pa.reference)
    c.failures.push_back(pe.dir + ": the exact reference differs (" + std::to_string(pe.reference.size()) +
                         " pairs in the golden, " + std::to_string(pa.reference.size()) +
                         " now): the two dumps are not of the same geometry");
  if (tier == Tier::exact || conservative) {
    if (!missing.empty())
      c.failures.push_back(pe.dir + ": " + std::to_string(missing.size()) + " golden colliding pairs missing:" +
                           list_pairs(missing));
    if (!extra.empty())
      c.failures.push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" +
                           list_pairs(extra));
  } else {
    // Misses against the reference (the golden's own colliding pairs where it has none).
    const Pairs& reference = pe.has_reference ? pe.reference : pe.colliding;
    const auto misses = [&](const Pairs& found) {
      Pairs m;
      std::set_difference(reference.begin(), reference.end(), found.begin(), found.end(), std::back_inserter(m));
      return m.size();
    };
    const std::size_t golden_misses = misses(pe.colliding), actual_misses = misses(pa.colliding);
    const std::size_t slack = hardware_miss_slack(reference.size());
    const std::string counts = std::to_string(actual_misses) + " of " + std::to_string(reference.size()) +
                               (pe.has_reference ? " reference" : " golden") + " pairs missed, golden " +
                               std::to_string(golden_misses) + ", slack " + std::to_string(slack);
    if (actual_misses > golden_misses + slack)
      c.failures.push_back(pe.dir + ": " + counts + "; golden pairs missing:" + list_pairs(missing));
    else if (!missing.empty())
      c.notes.push_back(pe.dir + ": " + counts + " (within the bound); golden pairs missing:" + list_pairs(missing));
    if (!extra.empty())
      c.notes.push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" +
                        list_pairs(extra));
  }
  if (pe.pcs != pa.pcs)
    (tier == Tier::exact ? c.failures : c.notes)
        .push_back(pe.dir + ": PCS differs: golden " + std::to_string(pe.pcs.size()) + " pairs, now " +
                   std::to_string(pa.pcs.size()));
}

// A view's record: resolution (false: its layers cannot be compared), PCS threshold, peel
// order, layer count, PCS.
bool compare_view_record(const DumpView& ve, const DumpView& va, Tier tier, Comparison& c) {
  if (ve.resolution != va.resolution) {
    c.failures.push_back(ve.dir + ": resolution differs: golden " + std::to_string(ve.resolution) + ", now " +
                         std::to_string(va.resolution));
    return false;
  }
  const double rel = tier == Tier::exact ? 0.0 : kThresholdRelative;
  if (!close_relative(ve.epsilon_window, va.epsilon_window, rel) || !close_relative(ve.slope, va.slope, rel))
    c.failures.push_back(ve.dir + ": PCS threshold differs: golden epsilon_window " + std::to_string(ve.epsilon_window) +
                         " slope " + std::to_string(ve.slope) + ", now " + std::to_string(va.epsilon_window) + " " +
                         std::to_string(va.slope));
  if (ve.a_first != va.a_first)
    c.failures.push_back(ve.dir + ": peel order differs: golden peels " + (ve.a_first ? "A" : "B") + " first");
  if (ve.layers.size() != va.layers.size())
    (tier == Tier::exact ? c.failures : c.notes)
        .push_back(ve.dir + ": " + std::to_string(va.layers.size()) + " layers, golden " +
                   std::to_string(ve.layers.size()));
  if (tier == Tier::exact && ve.pcs != va.pcs)
    c.failures.push_back(ve.dir + ": this view's PCS differs: golden " + std::to_string(ve.pcs.size()) +
                         " pairs, now " + std::to_string(va.pcs.size()));
  return true;
}

// How the hardware tier judges one view's texels.
struct TexelRule {
  Tier tier = Tier::exact;
  bool conservative = false;  // layers hold depth intervals: word 2 is the upper depth, word 3 is 0
  bool shared_ids = false;    // ring and paper IDs name several triangles (edges inside one ID)
  double depth_tolerance = 0.0;
  // Per texel, the layer from which the texel may differ (both sides' layers are looked at:
  // either rasterizer may be the one that broke the tie or sampled the sliver): ties
  // (first_tie_layer) and, with point sampling, one fragment more at an edge or a sliver inside
  // one ID (first_sliver_shift). `none`: no such layer.
  std::vector<std::size_t> tie_from;
};

TexelRule texel_rule(const Dump& e, const DumpView& ve, const DumpView& va, Tier tier, bool conservative) {
  TexelRule r;
  r.tier = tier;
  r.conservative = conservative;
  r.shared_ids = e.options.value("ids", std::string("unique")) != "unique";
  r.depth_tolerance = std::max(kDepthTolerance, kDepthFractionOfEpsilon * double(ve.epsilon_window));
  const int n = ve.resolution;
  const std::size_t none = ve.layers.size() + va.layers.size();
  r.tie_from.assign(std::size_t(n) * n, none);
  if (tier != Tier::hardware) return r;
  for (std::size_t t = 0; t < r.tie_from.size(); ++t) {
    r.tie_from[t] = std::min(first_tie_layer(ve.layers, t, r.depth_tolerance, none),
                             first_tie_layer(va.layers, t, r.depth_tolerance, none));
    if (!conservative)
      r.tie_from[t] = std::min(r.tie_from[t], first_sliver_shift(ve.layers, va.layers, t, r.depth_tolerance, none));
  }
  return r;
}

// Whether the hardware tier tolerates word `ch` of texel t (image x, GL row) of layer k
// differing: past a tie; another surface only next to an edge; a depth of the same surface
// within the tolerance (steep triangles: a vertex snapped to another sub-texel grid moves the
// depth plane by up to kSnapTexels times the texel's depth slope; shared IDs: the depths of the
// same ID around); slopes always (they follow the rasterizer's quad layout), the conservative
// word 3 never.
bool tolerated_word(const TexelRule& r, const std::vector<std::uint32_t>& le, const std::vector<std::uint32_t>& la,
                    int n, std::size_t k, int x, int gl_row, int ch) {
  if (r.tier != Tier::hardware) return false;
  const std::size_t t = std::size_t(gl_row) * n + x;
  if (k >= r.tie_from[t]) return true;
  const bool same_surface = texel::word(le, t, texel::kKey) == texel::word(la, t, texel::kKey);
  if (ch == 1 || !same_surface) return near_edge(le, n, x, gl_row, kIdSilhouetteTexels);
  if (ch == 0 || (r.conservative && ch == 2)) {
    const double slope =
        r.conservative ? 0.0 : std::fabs(texel::value(le, t, texel::kDzdx)) + std::fabs(texel::value(le, t, texel::kDzdy));
    const std::uint32_t we = le[4 * t + ch], wa = la[4 * t + ch];
    return depth_distance(we, wa) <= std::max(r.depth_tolerance, kSnapTexels * slope) ||
           (r.shared_ids && within_neighbour_depths(le, n, x, gl_row, as_float(wa), r.depth_tolerance));
  }
  return !r.conservative;
}

// A differing texel as the report lists it (image coordinates, y = 0 at the top).
TexelDifference describe_difference(const std::string& view_dir, std::size_t k, int x, int y, int ch, std::uint32_t we,
                                    std::uint32_t wa) {
  static const char* const kChannel[4] = {"Z", "id/object", "dzdx", "dzdy"};
  TexelDifference d{view_dir, k, x, y, kChannel[ch], hex(we), hex(wa)};
  if (ch == 0 || ch >= 2) {
    char buf[64];
    std::snprintf(buf, sizeof buf, " (%.9g)", as_float(we));
    d.expected += buf;
    std::snprintf(buf, sizeof buf, " (%.9g)", as_float(wa));
    d.actual += buf;
  } else {
    const auto desc = [](std::uint32_t w) {
      return w == 0 ? std::string(" (empty)")
                    : " (object " + std::string((w >> 31) ? "B" : "A") + ", ID " + std::to_string((w & 0x7fffffffu) - 1) +
                          ")";
    };
    d.expected += desc(we);
    d.actual += desc(wa);
  }
  return d;
}

// Layer k, which both sides have: texels visited in image order (top row first) so that "first"
// matches the files; one count per texel (its first differing word is the one listed).
Comparison::LayerCount compare_layer(const TexelRule& r, const DumpView& ve, const DumpView& va, std::size_t k,
                                     std::size_t max_listed, Comparison& c) {
  const auto &le = ve.layers[k], &la = va.layers[k];
  const int n = ve.resolution;
  Comparison::LayerCount count{ve.dir, k, 0, 0, std::vector<std::uint8_t>(std::size_t(n) * n, 0)};
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int gl_row = n - 1 - y;
      const std::size_t t = std::size_t(gl_row) * n + x;
      std::uint8_t& state = count.texels[std::size_t(y) * n + x];
      for (int ch = 0; ch < 4; ++ch) {
        const std::uint32_t we = le[4 * t + ch], wa = la[4 * t + ch];
        if (we == wa) continue;
        if (tolerated_word(r, le, la, n, k, x, gl_row, ch)) {
          state = 1;
          continue;
        }
        state = 2;
        if (c.first.size() < max_listed) c.first.push_back(describe_difference(ve.dir, k, x, y, ch, we, wa));
        break;
      }
      // One count per texel: beyond the tolerance if any word is, else within it if any word
      // differs.
      count.differing += state == 2;
      count.tolerated += state == 1;
    }
  if (!count.differing && !count.tolerated) count.texels.clear();
  return count;
}

// Layer k, which only the longer side has: every non-empty texel differs, except, on the
// hardware tier, texels past a tie or next to an edge of that layer (a sliver another
// rasterizer samples or not).
Comparison::LayerCount compare_lone_layer(const TexelRule& r, const std::string& view_dir,
                                          const std::vector<std::uint32_t>& layer, int n, std::size_t k) {
  Comparison::LayerCount count{view_dir, k, 0, 0, std::vector<std::uint8_t>(std::size_t(n) * n, 0)};
  for (int row = 0; row < n; ++row)
    for (int x = 0; x < n; ++x) {
      const std::size_t t = std::size_t(row) * n + x;
      if (texel_empty(layer, t)) continue;
      std::uint8_t& state = count.texels[std::size_t(n - 1 - row) * n + x];
      if (r.tier == Tier::hardware && (k >= r.tie_from[t] || near_edge(layer, n, x, row, kIdSilhouetteTexels))) {
        ++count.tolerated;
        state = 1;
      } else {
        ++count.differing;
        state = 2;
      }
    }
  if (!count.differing && !count.tolerated) count.texels.clear();
  return count;
}

void add_count(const Comparison::LayerCount& count, bool always, Comparison& c) {
  c.differing_texels += count.differing;
  c.tolerated_texels += count.tolerated;
  if (always || count.differing || count.tolerated) c.per_layer.push_back(count);
}

// A view's layers: those both sides have, then those only one has.
void compare_view_layers(const Dump& e, const DumpView& ve, const DumpView& va, Tier tier, bool conservative,
                         std::size_t max_listed, Comparison& c) {
  const TexelRule rule = texel_rule(e, ve, va, tier, conservative);
  const std::size_t layers = std::min(ve.layers.size(), va.layers.size());
  for (std::size_t k = 0; k < layers; ++k) add_count(compare_layer(rule, ve, va, k, max_listed, c), false, c);
  const auto& longer = ve.layers.size() > va.layers.size() ? ve.layers : va.layers;
  for (std::size_t k = layers; k < longer.size(); ++k)
    add_count(compare_lone_layer(rule, ve.dir, longer[k], ve.resolution, k), true, c);
}

}  // namespace

Comparison compare_dumps(const Dump& e, const Dump& a, Tier tier, std::size_t max_listed) {
  Comparison c;
  const bool conservative = e.options.value("conservative", false);
  if (!compare_header(e, a, c)) return c;
  for (std::size_t i = 0; i < e.pairs.size(); ++i) {
    const DumpPair &pe = e.pairs[i], &pa = a.pairs[i];
    if (pe.dir != pa.dir) {
      c.failures.push_back("ROI " + std::to_string(i) + " is " + pa.dir + ", golden " + pe.dir);
      continue;
    }
    compare_pair_contacts(pe, pa, tier, conservative, c);
    if (pe.views.size() != pa.views.size()) {
      c.failures.push_back(pe.dir + ": view count differs: golden " + std::to_string(pe.views.size()) + ", now " +
                           std::to_string(pa.views.size()));
      continue;
    }
    for (std::size_t v = 0; v < pe.views.size(); ++v)
      if (compare_view_record(pe.views[v], pa.views[v], tier, c))
        compare_view_layers(e, pe.views[v], pa.views[v], tier, conservative, max_listed, c);
  }
  return c;
}

std::string report_text(const Comparison& c, const std::string& case_name, Tier tier) {
  std::ostringstream s;
  s << "golden " << case_name << " (" << to_string(tier) << " tier): "
    << (c.ok() ? "match" : "DIFFERENT") << "\n";
  for (const std::string& f : c.failures) s << "  fail: " << f << "\n";
  for (const std::string& n : c.notes) s << "  note: " << n << "\n";
  if (c.differing_texels || c.tolerated_texels) {
    s << "  differing texels: " << c.differing_texels;
    if (tier == Tier::hardware) s << " (plus " << c.tolerated_texels << " within tolerance)";
    s << "\n";
    for (const auto& l : c.per_layer)
      s << "    " << l.view_dir << " " << layer_name(l.layer) << ": " << l.differing << " differing"
        << (tier == Tier::hardware ? ", " + std::to_string(l.tolerated) + " tolerated" : std::string()) << "\n";
    if (!c.first.empty()) s << "  first differing texels (layer, x, y, channel, expected, actual):\n";
    for (const TexelDifference& d : c.first)
      s << "    " << d.view_dir << " " << layer_name(d.layer) << " x=" << d.x << " y=" << d.y << " " << d.channel
        << ": expected " << d.expected << ", actual " << d.actual << "\n";
  }
  return s.str();
}

namespace {

// Two dumps' differing layers side by side (write_report()): expected | actual | error, and on
// hover the texel's words in both; the status line counts the texels marked (a test reads it).
std::string diff_page(const std::string& case_name, const std::string& report, const std::string& figures,
                      const std::string& data) {
  std::ostringstream h;
  std::string safe_report;
  for (char ch : report) safe_report += ch == '<' ? std::string("&lt;") : ch == '&' ? std::string("&amp;") : std::string(1, ch);
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>peelcd: " << case_name
    << ", two dumps</title>\n<style>body{font-family:sans-serif;background:#15151c;color:#ddd;margin:1em}"
       ".row{display:flex;gap:10px}figure{margin:0}img{image-rendering:pixelated;width:384px;border:1px solid #333;"
       "cursor:crosshair}#readout{font-family:monospace;color:#9f9;position:sticky;top:0;background:#15151c;"
       "padding:6px 0}pre{font-size:12px;color:#aaa}</style>\n<script>\nvar layers=["
    << data << "];\n" << R"JS(
function bytes(b64){var s=atob(b64),u=new Uint8Array(s.length);for(var i=0;i<s.length;++i)u[i]=s.charCodeAt(i);return u;}
function f32(w){var b=new ArrayBuffer(4);new Uint32Array(b)[0]=w;return new Float32Array(b)[0];}
layers.forEach(function(L){L.e=new Uint32Array(bytes(L.expected).buffer);L.a=new Uint32Array(bytes(L.actual).buffer);L.m=bytes(L.mask);});
function texel(W,t){var id1=W[4*t+1]&0x7fffffff;if(id1===0)return 'empty';
  return ((W[4*t+1]>>>31)?'B':'A')+' ID '+(id1-1)+' depth '+f32(W[4*t]).toPrecision(9)+' ['+W[4*t+2]+', '+W[4*t+3]+']';}
function readout(img,e){var L=layers[+img.dataset.layer],n=L.n;
  var x=Math.min(n-1,Math.floor(e.offsetX*n/img.clientWidth)),y=Math.min(n-1,Math.floor(e.offsetY*n/img.clientHeight));
  var t=(n-1-y)*n+x,s=['the same','within the tolerance','BEYOND the tolerance'][L.m[y*n+x]];
  document.getElementById('readout').textContent=L.name+' texel ('+x+', '+y+'): '+s+'; expected '+texel(L.e,t)+'; actual '+texel(L.a,t);}
window.addEventListener('load',function(){var beyond=0,within=0;
  layers.forEach(function(L){for(var i=0;i<L.m.length;++i){if(L.m[i]===2)beyond++;else if(L.m[i]===1)within++;}});
  document.querySelectorAll('img').forEach(function(i){i.addEventListener('mousemove',function(e){readout(i,e);});});
  var s=document.getElementById('status');s.setAttribute('data-status','ok');
  s.textContent='diff ok: '+layers.length+' layers, '+beyond+' texels beyond the tolerance, '+within+' within, marked';});
)JS" << "</script></head><body>\n<h1>" << case_name << ": two dumps, texel by texel</h1>\n"
    << "<p id=\"status\" data-status=\"pending\">loading</p>\n<p id=\"readout\">hover a layer for both dumps' words "
       "there</p>\n<p>Error pictures: <span style=\"color:#f00\">red</span> beyond the tier's tolerance, <span "
       "style=\"color:#fd0\">yellow</span> within it, grey the same, black empty.</p>\n"
    << figures << "<pre>" << safe_report << "</pre>\n</body></html>\n";
  return h.str();
}

}  // namespace

std::string write_report(const Dump& e, const Dump& a, const Comparison& c, const std::string& case_name,
                         const std::string& dir, std::size_t max_layers) {
  const Tier tier = c.tolerated_texels ? Tier::hardware : Tier::exact;
  std::string text = report_text(c, case_name, tier);
  fs::create_directories(dir);
  std::size_t written = 0;
  std::ostringstream figures, data;  // the page's figures and its layers' words and masks
  for (const auto& l : c.per_layer) {
    if (written >= max_layers || (!l.differing && !l.tolerated) || l.texels.empty()) continue;
    const DumpView* ve = nullptr;
    const DumpView* va = nullptr;
    for (const DumpPair& p : e.pairs)
      for (const DumpView& v : p.views)
        if (v.dir == l.view_dir) ve = &v;
    for (const DumpPair& p : a.pairs)
      for (const DumpView& v : p.views)
        if (v.dir == l.view_dir) va = &v;
    if (!ve || !va) continue;
    const int n = ve->resolution;
    const std::vector<std::uint32_t> empty(std::size_t(n) * n * 4, 0);
    const auto& le = l.layer < ve->layers.size() ? ve->layers[l.layer] : empty;
    const auto& la = l.layer < va->layers.size() ? va->layers[l.layer] : empty;
    std::string stem = l.view_dir + "_" + layer_name(l.layer);
    std::replace(stem.begin(), stem.end(), '/', '_');
    const fs::path base = fs::path(dir) / stem;
    write_png(base.string() + "_expected.png", layer_preview(le, n, {}));
    write_png(base.string() + "_actual.png", layer_preview(la, n, {}));
    // The error picture: red beyond the tier's tolerance, yellow within it, grey the same
    // (a surface), black empty.
    Rgb mask(n, n);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t t = std::size_t(n - 1 - y) * n + x;
        const std::uint8_t state = l.texels[std::size_t(y) * n + x];
        mask.set(x, y, state == 2   ? std::array<std::uint8_t, 3>{255, 0, 0}
                       : state == 1 ? std::array<std::uint8_t, 3>{255, 210, 0}
                       : texel_empty(le, t) && texel_empty(la, t) ? std::array<std::uint8_t, 3>{0, 0, 0}
                                                                  : std::array<std::uint8_t, 3>{70, 70, 70});
      }
    write_png(base.string() + "_error.png", mask);
    text += "  wrote " + base.string() + "_{expected,actual,error}.png\n";
    const std::string file = stem;  // the page lies beside the pictures
    figures << "<h2>" << l.view_dir << " " << layer_name(l.layer) << ": " << l.differing << " beyond the tolerance, "
            << l.tolerated << " within</h2>\n<div class=\"row\">";
    for (const char* which : {"expected", "actual", "error"})
      figures << "<figure><img data-layer=\"" << written << "\" src=\"" << file << "_" << which << ".png\" alt=\"" << which
              << "\"><figcaption>" << which << "</figcaption></figure>";
    figures << "</div>\n";
    data << (written ? ",\n" : "\n") << "{name:\"" << l.view_dir << " " << layer_name(l.layer) << "\",n:" << n
         << ",expected:\"" << layer_base64(le) << "\",actual:\"" << layer_base64(la) << "\",mask:\""
         << base64_bytes(l.texels) << "\"}";
    ++written;
  }
  write_text(fs::path(dir) / "report.txt", text);
  if (written) {
    write_text(fs::path(dir) / "index.html", diff_page(case_name, text, figures.str(), data.str()));
    text += "  page: " + (fs::path(dir) / "index.html").string() + "\n";
  }
  return text;
}

}  // namespace peelcd::oracle
