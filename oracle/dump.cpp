#include "peelcd/oracle/dump.h"

#include "peelcd/io/error.h"
#include "peelcd/io/options_json.h"
#include "peelcd/version.h"
#include "peelcd/oracle/viewer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace fs = std::filesystem;

namespace peelcd::oracle {
namespace {

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

std::string sanitize(const std::string& name) {
  std::string s;
  for (char c : name) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  return s.empty() ? "object" : s;
}

std::string layer_name(std::size_t k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "layer%02zu", k);
  return buf;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out.flush()) throw InputError("peelcd: cannot write '" + path.string() + "'");
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError("peelcd: cannot read '" + path.string() + "' (missing from the dump)");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string pcs_text(const std::vector<IdPair>& pcs) {
  std::string s;
  for (const IdPair& p : pcs) s += std::to_string(p.a) + " " + std::to_string(p.b) + "\n";
  return s;
}

std::vector<IdPair> parse_pcs(const std::string& text, const std::string& what) {
  std::vector<IdPair> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream l(line);
    IdPair p{};
    if (!(l >> p.a >> p.b)) throw InputError("peelcd: '" + what + "': malformed line \"" + line + "\"");
    out.push_back(p);
  }
  return out;
}

float as_float(std::uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

std::string hex(std::uint32_t w) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08x", w);
  return buf;
}

// Hardware tier tolerances (docs/design.md section 5).
// IDs may differ within this many texels of a silhouette or triangle edge of the golden layer:
// rasterizers snap vertices to different sub-texel grids, so a texel whose centre lies within
// rounding of an edge can be covered by either side.
constexpr int kIdSilhouetteTexels = 1;
// Depth may differ by this many float ULPs where the same triangle covers the texel: depth is
// interpolated from the plane equation in a different order and precision on other hardware.
constexpr std::int64_t kDepthUlps = 64;

std::int64_t ulp_distance(std::uint32_t a, std::uint32_t b) {
  // Map the float bit patterns to a monotonic integer line.
  const auto key = [](std::uint32_t w) -> std::int64_t {
    return (w & 0x80000000u) ? -std::int64_t(w & 0x7fffffffu) : std::int64_t(w);
  };
  return std::llabs(key(a) - key(b));
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

}  // namespace

const char* to_string(Tier tier) { return tier == Tier::exact ? "exact" : "hardware"; }

Dump make_dump(const FrameResult& frame, const std::vector<CapturedView>& captured,
               const std::vector<Object>& objects, const DetectOptions& o, const std::string& renderer,
               const std::string& gl_version, const std::string& backend) {
  Dump d;
  d.renderer = renderer;
  d.gl_version = gl_version;
  d.backend = backend;
  d.shader_hash = gl::shader_sources_hash();
  d.options = options_to_json(o);
  for (std::size_t i = 0; i < frame.pairs.size(); ++i) {
    const PairResult& r = frame.pairs[i];
    DumpPair p;
    p.name_a = objects[r.object_a].name;
    p.name_b = objects[r.object_b].name;
    p.object_a = r.object_a;
    p.object_b = r.object_b;
    p.dir = "pair" + std::to_string(i) + "_" + sanitize(p.name_a) + "_" + sanitize(p.name_b);
    p.epsilon = r.epsilon;
    p.pcs = r.pcs;
    for (const Contact& c : r.colliding) {
      p.colliding.push_back({c.tri_a, c.tri_b});
      p.kinds.push_back(to_string(c.kind));
    }
    for (const CapturedView& c : captured) {
      if (c.pair != i) continue;
      DumpView v;
      v.view = c.view;
      v.dir = p.dir + "/view" + std::to_string(c.view);
      v.resolution = c.roi.resolution;
      v.a_first = c.a_first;
      v.epsilon_window = c.epsilon_window;
      v.slope = c.slope;
      v.geometry = {{"center", vec(c.roi.center)}, {"u", vec(c.roi.frame.u)}, {"v", vec(c.roi.frame.v)},
                    {"d", vec(c.roi.frame.d)},      {"half_uv", c.roi.half_uv}, {"half_depth", c.roi.half_depth},
                    {"box_lo", vec(c.roi.box.lo)},  {"box_hi", vec(c.roi.box.hi)}};
      v.layers = c.layers;
      v.pcs = c.pcs;
      p.views.push_back(std::move(v));
    }
    d.pairs.push_back(std::move(p));
  }
  return d;
}

std::vector<bool> pcs_texels(const DumpView& view, std::size_t k) {
  const std::size_t count = std::size_t(view.resolution) * view.resolution;
  std::vector<bool> marks(count, false);
  if (k == 0 || k >= view.layers.size()) return marks;
  const auto& l0 = view.layers[k - 1];
  const auto& l1 = view.layers[k];
  for (std::size_t i = 0; i < count; ++i) {
    if (texel_empty(l0, i) || texel_empty(l1, i) || texel_object(l0, i) == texel_object(l1, i)) continue;
    const float dz = std::fabs(as_float(l1[4 * i]) - as_float(l0[4 * i]));
    const float spread = std::fabs(as_float(l1[4 * i + 2]) - as_float(l0[4 * i + 2])) +
                         std::fabs(as_float(l1[4 * i + 3]) - as_float(l0[4 * i + 3]));
    marks[i] = dz < view.epsilon_window + view.slope * spread;
  }
  return marks;
}

void write_dump(const Dump& d, const std::string& dir, bool previews) {
  const fs::path root(dir);
  if (fs::exists(root) && !(fs::is_directory(root) && fs::is_empty(root)))
    throw InputError("peelcd: --out '" + dir + "' exists and is not an empty folder");
  const fs::path tmp = root.string() + ".partial";
  std::error_code ec;
  fs::remove_all(tmp, ec);
  try {
    fs::create_directories(tmp);
    nlohmann::json meta = {{"peelcd_version", PEELCD_VERSION_STRING}, {"renderer", d.renderer},
                           {"gl_version", d.gl_version}, {"backend", d.backend},
                           {"shader_hash", d.shader_hash}, {"options", d.options}};
    nlohmann::json pairs = nlohmann::json::array();
    for (const DumpPair& p : d.pairs) {
      fs::create_directories(tmp / p.dir);
      write_text(tmp / p.dir / "pcs.txt", pcs_text(p.pcs));
      std::string col;
      for (std::size_t i = 0; i < p.colliding.size(); ++i)
        col += std::to_string(p.colliding[i][0]) + " " + std::to_string(p.colliding[i][1]) + " " + p.kinds[i] + "\n";
      write_text(tmp / p.dir / "colliding.txt", col);
      nlohmann::json views = nlohmann::json::array();
      for (const DumpView& v : p.views) {
        fs::create_directories(tmp / v.dir);
        write_text(tmp / v.dir / "pcs.txt", pcs_text(v.pcs));
        for (std::size_t k = 0; k < v.layers.size(); ++k) {
          write_layer_exr((tmp / v.dir / (layer_name(k) + ".exr")).string(), v.layers[k], v.resolution);
          if (previews)
            write_png((tmp / v.dir / (layer_name(k) + ".png")).string(),
                      layer_preview(v.layers[k], v.resolution, pcs_texels(v, k)));
        }
        views.push_back({{"dir", v.dir},
                         {"view", v.view},
                         {"resolution", v.resolution},
                         {"a_first", v.a_first},
                         {"epsilon_window", v.epsilon_window},
                         {"slope", v.slope},
                         {"layers", v.layers.size()},
                         {"pcs", v.pcs.size()},
                         {"geometry", v.geometry}});
      }
      pairs.push_back({{"dir", p.dir},
                       {"a", p.name_a},
                       {"b", p.name_b},
                       {"object_a", p.object_a},
                       {"object_b", p.object_b},
                       {"epsilon", p.epsilon},
                       {"pcs", p.pcs.size()},
                       {"colliding", p.colliding.size()},
                       {"views", views}});
    }
    meta["pairs"] = pairs;
    write_text(tmp / "meta.json", meta.dump(2) + "\n");
    if (previews) write_text(tmp / "index.html", viewer_html(d));
    if (fs::exists(root)) fs::remove(root);  // the empty folder checked above
    fs::rename(tmp, root);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

Dump read_dump(const std::string& dir) {
  const fs::path root(dir);
  Dump d;
  nlohmann::json meta;
  try {
    meta = nlohmann::json::parse(read_text(root / "meta.json"));
    d.renderer = meta.at("renderer").get<std::string>();
    d.gl_version = meta.at("gl_version").get<std::string>();
    d.backend = meta.at("backend").get<std::string>();
    d.shader_hash = meta.at("shader_hash").get<std::string>();
    d.options = meta.at("options");
    for (const auto& jp : meta.at("pairs")) {
      DumpPair p;
      p.dir = jp.at("dir").get<std::string>();
      p.name_a = jp.at("a").get<std::string>();
      p.name_b = jp.at("b").get<std::string>();
      p.object_a = jp.at("object_a").get<std::size_t>();
      p.object_b = jp.at("object_b").get<std::size_t>();
      p.epsilon = jp.at("epsilon").get<double>();
      p.pcs = parse_pcs(read_text(root / p.dir / "pcs.txt"), (root / p.dir / "pcs.txt").string());
      std::istringstream col(read_text(root / p.dir / "colliding.txt"));
      std::string line;
      while (std::getline(col, line)) {
        if (line.empty()) continue;
        std::istringstream l(line);
        std::array<std::uint32_t, 2> c{};
        std::string kind;
        if (!(l >> c[0] >> c[1] >> kind))
          throw InputError("peelcd: '" + (root / p.dir / "colliding.txt").string() + "': malformed line \"" + line + "\"");
        p.colliding.push_back(c);
        p.kinds.push_back(kind);
      }
      for (const auto& jv : jp.at("views")) {
        DumpView v;
        v.dir = jv.at("dir").get<std::string>();
        v.view = jv.at("view").get<int>();
        v.resolution = jv.at("resolution").get<int>();
        v.a_first = jv.at("a_first").get<bool>();
        v.epsilon_window = jv.at("epsilon_window").get<float>();
        v.slope = jv.at("slope").get<float>();
        v.geometry = jv.at("geometry");
        v.pcs = parse_pcs(read_text(root / v.dir / "pcs.txt"), (root / v.dir / "pcs.txt").string());
        const std::size_t layers = jv.at("layers").get<std::size_t>();
        for (std::size_t k = 0; k < layers; ++k) {
          int n = 0;
          v.layers.push_back(read_layer_exr((root / v.dir / (layer_name(k) + ".exr")).string(), n));
          if (n != v.resolution)
            throw InputError("peelcd: '" + (root / v.dir / (layer_name(k) + ".exr")).string() + "' is " +
                             std::to_string(n) + "^2, meta.json says " + std::to_string(v.resolution));
        }
        p.views.push_back(std::move(v));
      }
      d.pairs.push_back(std::move(p));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError("peelcd: '" + (root / "meta.json").string() + "': " + e.what());
  }
  return d;
}

Comparison compare_dumps(const Dump& e, const Dump& a, Tier tier, std::size_t max_listed) {
  Comparison c;
  if (e.shader_hash != a.shader_hash)
    c.notes.push_back("shader sources changed since the golden was recorded (hash " + e.shader_hash + ", now " +
                      a.shader_hash + ")");
  if (e.renderer != a.renderer) c.notes.push_back("renderer: golden \"" + e.renderer + "\", now \"" + a.renderer + "\"");
  // Options both dumps record must agree (a dump from an older writer may record fewer).
  for (const auto& [key, value] : e.options.items())
    if (a.options.contains(key) && a.options[key] != value)
      c.failures.push_back("option \"" + key + "\" differs: golden " + value.dump() + ", now " + a.options[key].dump());
  if (e.pairs.size() != a.pairs.size()) {
    c.failures.push_back("ROI count differs: golden " + std::to_string(e.pairs.size()) + ", now " +
                         std::to_string(a.pairs.size()));
    return c;
  }
  for (std::size_t i = 0; i < e.pairs.size(); ++i) {
    const DumpPair &pe = e.pairs[i], &pa = a.pairs[i];
    if (pe.dir != pa.dir) {
      c.failures.push_back("ROI " + std::to_string(i) + " is " + pa.dir + ", golden " + pe.dir);
      continue;
    }
    // Colliding pairs: the exact tier wants the same list; every tier wants every golden pair.
    std::vector<std::array<std::uint32_t, 2>> missing, extra;
    std::set_difference(pe.colliding.begin(), pe.colliding.end(), pa.colliding.begin(), pa.colliding.end(),
                        std::back_inserter(missing));
    std::set_difference(pa.colliding.begin(), pa.colliding.end(), pe.colliding.begin(), pe.colliding.end(),
                        std::back_inserter(extra));
    const auto list = [](const std::vector<std::array<std::uint32_t, 2>>& v) {
      std::string s;
      for (std::size_t k = 0; k < v.size() && k < 8; ++k) s += " (" + std::to_string(v[k][0]) + "," + std::to_string(v[k][1]) + ")";
      if (v.size() > 8) s += " ...";
      return s;
    };
    if (!missing.empty())
      c.failures.push_back(pe.dir + ": " + std::to_string(missing.size()) + " golden colliding pairs missing:" + list(missing));
    if (!extra.empty())
      (tier == Tier::exact ? c.failures : c.notes)
          .push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" + list(extra));
    if (pe.pcs != pa.pcs)
      (tier == Tier::exact ? c.failures : c.notes)
          .push_back(pe.dir + ": PCS differs: golden " + std::to_string(pe.pcs.size()) + " pairs, now " +
                     std::to_string(pa.pcs.size()));
    if (pe.views.size() != pa.views.size()) {
      c.failures.push_back(pe.dir + ": view count differs: golden " + std::to_string(pe.views.size()) + ", now " +
                           std::to_string(pa.views.size()));
      continue;
    }
    for (std::size_t v = 0; v < pe.views.size(); ++v) {
      const DumpView &ve = pe.views[v], &va = pa.views[v];
      if (ve.resolution != va.resolution) {
        c.failures.push_back(ve.dir + ": resolution differs: golden " + std::to_string(ve.resolution) + ", now " +
                             std::to_string(va.resolution));
        continue;
      }
      if (ve.epsilon_window != va.epsilon_window || ve.slope != va.slope || ve.a_first != va.a_first)
        c.failures.push_back(ve.dir + ": epsilon, slope or peel order differs from the golden");
      if (ve.layers.size() != va.layers.size())
        (tier == Tier::exact ? c.failures : c.notes)
            .push_back(ve.dir + ": " + std::to_string(va.layers.size()) + " layers, golden " +
                       std::to_string(ve.layers.size()));
      if (tier == Tier::exact && ve.pcs != va.pcs)
        c.failures.push_back(ve.dir + ": this view's PCS differs: golden " + std::to_string(ve.pcs.size()) +
                             " pairs, now " + std::to_string(va.pcs.size()));
      const int n = ve.resolution;
      const std::size_t layers = std::min(ve.layers.size(), va.layers.size());
      static const char* const kChannel[4] = {"Z", "id/object", "dzdx", "dzdy"};
      for (std::size_t k = 0; k < layers; ++k) {
        const auto &le = ve.layers[k], &la = va.layers[k];
        Comparison::LayerCount count{ve.dir, k, 0, 0};
        // Visit in image order (top row first) so "first" matches the files.
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            const int gl_row = n - 1 - y;
            const std::size_t t = std::size_t(gl_row) * n + x;
            for (int ch = 0; ch < 4; ++ch) {
              const std::uint32_t we = le[4 * t + ch], wa = la[4 * t + ch];
              if (we == wa) continue;
              bool tolerated = false;
              if (tier == Tier::hardware) {
                const bool same_surface = le[4 * t + 1] == la[4 * t + 1];
                if (ch == 1) tolerated = near_edge(le, n, x, gl_row, kIdSilhouetteTexels);
                else if (ch == 0) tolerated = !same_surface || ulp_distance(we, wa) <= kDepthUlps;
                else tolerated = true;  // derivatives follow the rasterizer's quad layout
                if (!same_surface && ch != 1) tolerated = near_edge(le, n, x, gl_row, kIdSilhouetteTexels);
              }
              if (tolerated) {
                ++count.tolerated;
                continue;
              }
              ++count.differing;
              if (c.first.size() < max_listed) {
                TexelDifference d{ve.dir, k, x, y, kChannel[ch], hex(we), hex(wa)};
                if (ch == 0 || ch >= 2) {
                  char buf[64];
                  std::snprintf(buf, sizeof buf, " (%.9g)", as_float(we));
                  d.expected += buf;
                  std::snprintf(buf, sizeof buf, " (%.9g)", as_float(wa));
                  d.actual += buf;
                } else {
                  const auto desc = [](std::uint32_t w) {
                    return w == 0 ? std::string(" (empty)")
                                  : " (object " + std::string((w >> 31) ? "B" : "A") + ", ID " +
                                        std::to_string((w & 0x7fffffffu) - 1) + ")";
                  };
                  d.expected += desc(we);
                  d.actual += desc(wa);
                }
                c.first.push_back(d);
              }
              break;  // one count per texel: the first differing channel is listed
            }
          }
        c.differing_texels += count.differing;
        c.tolerated_texels += count.tolerated;
        if (count.differing || count.tolerated) c.per_layer.push_back(count);
      }
      // Layers only one side has: every non-empty texel differs.
      const auto& longer = ve.layers.size() > va.layers.size() ? ve.layers : va.layers;
      for (std::size_t k = layers; k < longer.size(); ++k) {
        std::size_t filled = 0;
        for (std::size_t t = 0; t < std::size_t(n) * n; ++t) filled += !texel_empty(longer[k], t);
        if (tier == Tier::exact) c.differing_texels += filled;
        c.per_layer.push_back({ve.dir, k, tier == Tier::exact ? filled : 0, tier == Tier::exact ? 0 : filled});
      }
    }
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

std::string write_report(const Dump& e, const Dump& a, const Comparison& c, const std::string& case_name,
                         const std::string& dir, std::size_t max_layers) {
  const Tier tier = c.tolerated_texels ? Tier::hardware : Tier::exact;
  std::string text = report_text(c, case_name, tier);
  fs::create_directories(dir);
  std::size_t written = 0;
  for (const auto& l : c.per_layer) {
    if (written >= max_layers || !l.differing) continue;
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
    Rgb mask(n, n);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t t = std::size_t(n - 1 - y) * n + x;
        const bool differs = !std::equal(le.begin() + 4 * t, le.begin() + 4 * t + 4, la.begin() + 4 * t);
        mask.set(x, y, differs ? std::array<std::uint8_t, 3>{255, 0, 0}
                               : (texel_empty(le, t) ? std::array<std::uint8_t, 3>{0, 0, 0}
                                                     : std::array<std::uint8_t, 3>{70, 70, 70}));
      }
    write_png(base.string() + "_error.png", mask);
    text += "  wrote " + base.string() + "_{expected,actual,error}.png\n";
    ++written;
  }
  write_text(fs::path(dir) / "report.txt", text);
  return text;
}

}  // namespace peelcd::oracle
