#include "peelcd/oracle/dump.h"

#include "peelcd/core/kbuffer.h"

#include "peelcd/io/error.h"
#include "peelcd/core/reference.h"
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

Dump make_dump(const FrameResult& frame, const std::vector<CapturedView>& captured,
               const std::vector<Object>& objects, const DetectOptions& o, const std::string& renderer,
               const std::string& gl_version, const std::string& backend, const gl::GlOptions* gl) {
  Dump d;
  if (gl) d.gl_options = gl_options_to_json(*gl);
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
    p.has_reference = true;
    for (std::uint64_t key : exact_pair_reference(objects, r.object_a, r.object_b, o.self_adjacency))
      p.reference.push_back({std::uint32_t(key >> 32), std::uint32_t(key & 0xffffffffu)});
    for (const CapturedView& c : captured) {
      if (c.pair != i) continue;
      DumpView v;
      v.view = c.view;
      v.dir = p.dir + "/view" + std::to_string(c.view);
      v.resolution = c.roi.resolution;
      v.a_first = c.a_first;
      v.epsilon_window = c.epsilon_window;
      v.slope = c.slope;
      v.conservative = o.conservative;
      v.geometry = {{"center", vec(c.roi.center)}, {"u", vec(c.roi.frame.u)}, {"v", vec(c.roi.frame.v)},
                    {"d", vec(c.roi.frame.d)},      {"half_uv", c.roi.half_uv}, {"half_depth", c.roi.half_depth},
                    {"box_lo", vec(c.roi.box.lo)},  {"box_hi", vec(c.roi.box.hi)}};
      v.layers = c.layers;
      v.pcs = c.pcs;
      if (o.volume && r.object_a != r.object_b)  // the inside intervals, per texel (docs/design.md)
        v.inside_note = overlap_lengths(objects[r.object_a].mesh, objects[r.object_b].mesh, c.roi.center, c.roi.frame.u,
                                        c.roi.frame.v, c.roi.frame.d, c.roi.half_uv, c.roi.half_depth, c.roi.resolution,
                                        v.inside);
      p.views.push_back(std::move(v));
    }
    d.pairs.push_back(std::move(p));
  }
  return d;
}

std::vector<bool> pcs_texels(const DumpView& view, std::size_t k) {
  const std::size_t count = std::size_t(view.resolution) * view.resolution;
  std::vector<bool> marks(count, false);
  if (k >= view.layers.size()) return marks;
  const auto& lk = view.layers[k];
  if (view.conservative) {  // every layer of the other object whose interval overlaps layer k's
    for (std::size_t i = 0; i < count; ++i) {
      if (texel_empty(lk, i)) continue;
      for (std::size_t j = 0; j < view.layers.size() && !marks[i]; ++j) {
        const auto& lj = view.layers[j];
        if (j == k || texel_empty(lj, i) || texel_object(lj, i) == texel_object(lk, i)) continue;
        marks[i] = pcs_intervals_overlap(texel::value(lk, i, texel::kDepth), texel::value(lk, i, texel::kUpper),
                                         texel::value(lj, i, texel::kDepth), texel::value(lj, i, texel::kUpper));
      }
    }
    return marks;
  }
  if (k == 0) return marks;
  const auto& l0 = view.layers[k - 1];
  const auto& l1 = lk;
  for (std::size_t i = 0; i < count; ++i) {
    if (texel_empty(l0, i) || texel_empty(l1, i) || texel_object(l0, i) == texel_object(l1, i)) continue;
    const float spread = std::fabs(texel::value(l1, i, texel::kDzdx) - texel::value(l0, i, texel::kDzdx)) +
                         std::fabs(texel::value(l1, i, texel::kDzdy) - texel::value(l0, i, texel::kDzdy));
    marks[i] = pcs_within_epsilon(texel::value(l0, i, texel::kDepth), texel::value(l1, i, texel::kDepth), spread,
                                  view.epsilon_window, view.slope);
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
    nlohmann::json meta = {{"format", d.format}, {"peelcd_version", PEELCD_VERSION_STRING}, {"renderer", d.renderer},
                           {"gl_version", d.gl_version}, {"backend", d.backend},
                           {"shader_hash", d.shader_hash}, {"options", d.options}};
    if (!d.gl_options.is_null()) meta["gl_options"] = d.gl_options;
    nlohmann::json pairs = nlohmann::json::array();
    for (const DumpPair& p : d.pairs) {
      fs::create_directories(tmp / p.dir);
      write_text(tmp / p.dir / "pcs.txt", pcs_text(p.pcs));
      std::string col;
      for (std::size_t i = 0; i < p.colliding.size(); ++i)
        col += std::to_string(p.colliding[i][0]) + " " + std::to_string(p.colliding[i][1]) + " " + p.kinds[i] + "\n";
      write_text(tmp / p.dir / "colliding.txt", col);
      if (p.has_reference) {
        std::string ref;
        for (const auto& r : p.reference) ref += std::to_string(r[0]) + " " + std::to_string(r[1]) + "\n";
        write_text(tmp / p.dir / "reference.txt", ref);
      }
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
        if (!v.inside.empty()) {  // inside.png: length where both are inside, white = the longest
          float longest = 0.0f;
          double sum = 0.0;
          for (const float x : v.inside) {
            longest = std::max(longest, x);
            sum += x;
          }
          const int n = v.resolution;
          Rgb image(n, n);
          for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
              const float x = v.inside[std::size_t(j) * n + i];
              const auto g = std::uint8_t(longest > 0 ? 40.0f + 215.0f * x / longest : 0.0f);
              image.set(i, n - 1 - j, x > 0 ? std::array<std::uint8_t, 3>{g, g, g} : std::array<std::uint8_t, 3>{0, 0, 0});
            }
          write_png((tmp / v.dir / "inside.png").string(), image);
          const double texel = 2.0 * v.geometry.value("half_uv", 0.0) / n;
          views.back()["inside"] = {{"file", "inside.png"}, {"longest", longest}, {"volume", sum * texel * texel}};
        } else if (!v.inside_note.empty()) {
          views.back()["inside"] = {{"unknown", v.inside_note}};
        }
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
      if (p.has_reference) pairs.back()["reference"] = p.reference.size();
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

namespace {

// "a b [kind]" lines (kind only where `kinds` is given), sorted on reading.
std::vector<std::array<std::uint32_t, 2>> parse_pairs(const fs::path& path, std::vector<std::string>* kinds) {
  std::istringstream in(read_text(path));
  std::vector<std::pair<std::array<std::uint32_t, 2>, std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream l(line);
    std::array<std::uint32_t, 2> c{};
    std::string kind, rest;
    if (!(l >> c[0] >> c[1]) || (kinds && !(l >> kind)) || (l >> rest))
      throw InputError("peelcd: '" + path.string() + "': malformed line \"" + line + "\" (expected \"triA triB" +
                       std::string(kinds ? " kind" : "") + "\")");
    rows.push_back({c, kind});
  }
  std::sort(rows.begin(), rows.end());
  std::vector<std::array<std::uint32_t, 2>> out;
  for (auto& [c, kind] : rows) {
    out.push_back(c);
    if (kinds) kinds->push_back(kind);
  }
  return out;
}

void check_count(const nlohmann::json& j, const char* key, std::size_t actual, const fs::path& file,
                 const fs::path& meta) {
  if (j.contains(key) && j.at(key).get<std::size_t>() != actual)
    throw InputError("peelcd: '" + file.string() + "' has " + std::to_string(actual) + " lines, '" + meta.string() +
                     "' says " + key + " = " + std::to_string(j.at(key).get<std::size_t>()));
}

}  // namespace

Dump read_dump(const std::string& dir) {
  const fs::path root(dir);
  const fs::path meta_path = root / "meta.json";
  if (!fs::is_directory(root)) throw InputError("peelcd: '" + dir + "' is not a dump folder (not a folder)");
  Dump d;
  nlohmann::json meta;
  try {
    try {
      meta = nlohmann::json::parse(read_text(meta_path));
    } catch (const nlohmann::json::parse_error& e) {
      throw InputError("peelcd: '" + meta_path.string() + "' is not valid JSON: " + e.what());
    }
    if (!meta.is_object()) throw InputError("peelcd: '" + meta_path.string() + "' is not a JSON object");
    // Dumps written before the format was named have no "format"; they are format 1.
    d.format = meta.value("format", std::string(kDumpFormat));
    if (d.format != kDumpFormat)
      throw InputError("peelcd: '" + meta_path.string() + "': format \"" + d.format + "\" is not " + kDumpFormat);
    d.renderer = meta.at("renderer").get<std::string>();
    d.gl_version = meta.at("gl_version").get<std::string>();
    d.backend = meta.at("backend").get<std::string>();
    d.shader_hash = meta.at("shader_hash").get<std::string>();
    d.options = meta.at("options");
    if (!d.options.is_object()) throw InputError("peelcd: '" + meta_path.string() + "': \"options\" is not an object");
    if (meta.contains("gl_options")) d.gl_options = meta.at("gl_options");
    for (const auto& jp : meta.at("pairs")) {
      DumpPair p;
      p.dir = jp.at("dir").get<std::string>();
      p.name_a = jp.at("a").get<std::string>();
      p.name_b = jp.at("b").get<std::string>();
      p.object_a = jp.at("object_a").get<std::size_t>();
      p.object_b = jp.at("object_b").get<std::size_t>();
      p.epsilon = jp.at("epsilon").get<double>();
      if (p.dir.empty() || p.dir.find("..") != std::string::npos || p.dir.front() == '/')
        throw InputError("peelcd: '" + meta_path.string() + "': pair dir \"" + p.dir + "\" is not a relative folder name");
      p.pcs = parse_pcs(read_text(root / p.dir / "pcs.txt"), (root / p.dir / "pcs.txt").string());
      std::sort(p.pcs.begin(), p.pcs.end());
      check_count(jp, "pcs", p.pcs.size(), root / p.dir / "pcs.txt", meta_path);
      p.colliding = parse_pairs(root / p.dir / "colliding.txt", &p.kinds);
      check_count(jp, "colliding", p.colliding.size(), root / p.dir / "colliding.txt", meta_path);
      if (jp.contains("reference") || fs::exists(root / p.dir / "reference.txt")) {
        p.has_reference = true;
        p.reference = parse_pairs(root / p.dir / "reference.txt", nullptr);
        check_count(jp, "reference", p.reference.size(), root / p.dir / "reference.txt", meta_path);
      }
      for (const auto& jv : jp.at("views")) {
        DumpView v;
        v.dir = jv.at("dir").get<std::string>();
        v.view = jv.at("view").get<int>();
        v.resolution = jv.at("resolution").get<int>();
        v.a_first = jv.at("a_first").get<bool>();
        v.epsilon_window = jv.at("epsilon_window").get<float>();
        v.slope = jv.at("slope").get<float>();
        v.conservative = d.options.value("conservative", false);
        v.geometry = jv.value("geometry", nlohmann::json::object());
        if (v.dir.find("..") != std::string::npos || v.dir.empty() || v.dir.front() == '/')
          throw InputError("peelcd: '" + meta_path.string() + "': view dir \"" + v.dir + "\" is not a relative folder name");
        if (v.resolution < 1 || v.resolution > 16384)
          throw InputError("peelcd: '" + meta_path.string() + "': view " + v.dir + ": resolution " +
                           std::to_string(v.resolution) + " is outside 1..16384");
        v.pcs = parse_pcs(read_text(root / v.dir / "pcs.txt"), (root / v.dir / "pcs.txt").string());
        std::sort(v.pcs.begin(), v.pcs.end());
        check_count(jv, "pcs", v.pcs.size(), root / v.dir / "pcs.txt", meta_path);
        const std::size_t layers = jv.at("layers").get<std::size_t>();
        for (std::size_t k = 0; k < layers; ++k) {
          const fs::path file = root / v.dir / (layer_name(k) + ".exr");
          if (!fs::exists(file))
            throw InputError("peelcd: '" + file.string() + "' is missing (" + meta_path.string() + " says view " +
                             v.dir + " has " + std::to_string(layers) + " layers)");
          int n = 0;
          v.layers.push_back(read_layer_exr(file.string(), n));
          if (n != v.resolution)
            throw InputError("peelcd: '" + file.string() + "' is " + std::to_string(n) + "^2, meta.json says " +
                             std::to_string(v.resolution));
        }
        p.views.push_back(std::move(v));
      }
      d.pairs.push_back(std::move(p));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError("peelcd: '" + meta_path.string() + "': " + e.what());
  }
  return d;
}

Comparison compare_dumps(const Dump& e, const Dump& a, Tier tier, std::size_t max_listed) {
  Comparison c;
  // The conservative mode's layers hold depth intervals: word 2 is the upper depth, word 3 is 0.
  const bool conservative = e.options.value("conservative", false);
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
    // Colliding pairs. The exact tier wants the same list. The hardware tier wants the same list
    // in the conservative mode (it must find every contact whatever the rasterizer) and, in a
    // lossy configuration, no more misses against the exact reference than the golden's plus
    // hardware_miss_slack(); extra pairs are exactly verified contacts, listed as notes.
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
    if (pe.has_reference && pa.has_reference && pe.reference != pa.reference)
      c.failures.push_back(pe.dir + ": the exact reference differs (" + std::to_string(pe.reference.size()) +
                           " pairs in the golden, " + std::to_string(pa.reference.size()) +
                           " now): the two dumps are not of the same geometry");
    const bool strict_pairs = tier == Tier::exact || conservative;
    if (strict_pairs) {
      if (!missing.empty())
        c.failures.push_back(pe.dir + ": " + std::to_string(missing.size()) + " golden colliding pairs missing:" + list(missing));
      if (!extra.empty())
        c.failures.push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" + list(extra));
    } else {
      // Misses against the reference (the golden's own colliding pairs where it has none).
      const auto& reference = pe.has_reference ? pe.reference : pe.colliding;
      const auto misses = [&](const std::vector<std::array<std::uint32_t, 2>>& found) {
        std::vector<std::array<std::uint32_t, 2>> m;
        std::set_difference(reference.begin(), reference.end(), found.begin(), found.end(), std::back_inserter(m));
        return m.size();
      };
      const std::size_t golden_misses = misses(pe.colliding), actual_misses = misses(pa.colliding);
      const std::size_t slack = hardware_miss_slack(reference.size());
      const std::string counts = std::to_string(actual_misses) + " of " + std::to_string(reference.size()) +
                                 (pe.has_reference ? " reference" : " golden") + " pairs missed, golden " +
                                 std::to_string(golden_misses) + ", slack " + std::to_string(slack);
      if (actual_misses > golden_misses + slack)
        c.failures.push_back(pe.dir + ": " + counts + "; golden pairs missing:" + list(missing));
      else if (!missing.empty())
        c.notes.push_back(pe.dir + ": " + counts + " (within the bound); golden pairs missing:" + list(missing));
      if (!extra.empty())
        c.notes.push_back(pe.dir + ": " + std::to_string(extra.size()) + " colliding pairs not in the golden:" + list(extra));
    }
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
      const int n = ve.resolution;
      // Ring and paper IDs name several triangles: edges inside one ID are invisible to near_edge.
      const bool shared_ids = e.options.value("ids", std::string("unique")) != "unique";
      const double depth_tolerance = std::max(kDepthTolerance, kDepthFractionOfEpsilon * double(ve.epsilon_window));
      const std::size_t layers = std::min(ve.layers.size(), va.layers.size());
      // Where the hardware tier lets a texel differ from some layer on (both sides' layers are
      // looked at: either rasterizer may be the one that broke the tie or sampled the sliver):
      // ties (first_tie_layer) and, with point sampling, one fragment more at an edge or a sliver
      // inside one ID (first_sliver_shift).
      const std::size_t none = ve.layers.size() + va.layers.size();
      std::vector<std::size_t> tie_from(std::size_t(n) * n, none);
      if (tier == Tier::hardware)
        for (std::size_t t = 0; t < tie_from.size(); ++t) {
          tie_from[t] = std::min(first_tie_layer(ve.layers, t, depth_tolerance, none),
                                 first_tie_layer(va.layers, t, depth_tolerance, none));
          if (!conservative)
            tie_from[t] = std::min(tie_from[t], first_sliver_shift(ve.layers, va.layers, t, depth_tolerance, none));
        }
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
              if (tier == Tier::hardware && k >= tie_from[t]) {
                tolerated = true;
              } else if (tier == Tier::hardware) {
                const bool same_surface = texel::word(le, t, texel::kKey) == texel::word(la, t, texel::kKey);
                if (ch == 1 || !same_surface)  // another surface: only next to an edge
                  tolerated = near_edge(le, n, x, gl_row, kIdSilhouetteTexels);
                else if (ch == 0 || (conservative && ch == 2)) {  // a depth of the same surface
                  // Steep triangles: a vertex snapped to another sub-texel grid moves the depth
                  // plane by up to kSnapTexels times the texel's depth slope.
                  const double slope =
                      conservative ? 0.0 : std::fabs(texel::value(le, t, texel::kDzdx)) + std::fabs(texel::value(le, t, texel::kDzdy));
                  tolerated = depth_distance(we, wa) <= std::max(depth_tolerance, kSnapTexels * slope) ||
                              (shared_ids && within_neighbour_depths(le, n, x, gl_row, as_float(wa), depth_tolerance));
                }
                else  // slopes follow the rasterizer's quad layout; the conservative word 3 is 0
                  tolerated = !conservative;
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
      // Layers only one side has: every non-empty texel differs, except, on the hardware tier,
      // texels next to an edge of that layer (a sliver another rasterizer samples or not).
      const auto& longer = ve.layers.size() > va.layers.size() ? ve.layers : va.layers;
      for (std::size_t k = layers; k < longer.size(); ++k) {
        Comparison::LayerCount count{ve.dir, k, 0, 0};
        for (int row = 0; row < n; ++row)
          for (int x = 0; x < n; ++x) {
            const std::size_t t = std::size_t(row) * n + x;
            if (texel_empty(longer[k], t)) continue;
            if (tier == Tier::hardware && (k >= tie_from[t] || near_edge(longer[k], n, x, row, kIdSilhouetteTexels)))
              ++count.tolerated;
            else ++count.differing;
          }
        c.differing_texels += count.differing;
        c.tolerated_texels += count.tolerated;
        c.per_layer.push_back(count);
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
