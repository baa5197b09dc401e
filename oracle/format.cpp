#include "peelcd/oracle/format.h"

#include "peelcd/core/exact/relation.h"
#include "peelcd/oracle/images.h"
#include "text_file.h"

#include "peelcd/core/image/kbuffer.h"

#include "peelcd/io/error.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/io/options_json.h"
#include "peelcd/version.h"
#include "peelcd/oracle/viewer.h"

#include <algorithm>
#include <iterator>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace fs = std::filesystem;

namespace peelcd::oracle {

std::vector<std::array<std::uint32_t, 2>> missed_pairs(const DumpPair& p) {
  std::vector<std::array<std::uint32_t, 2>> out;
  std::set_difference(p.reference.begin(), p.reference.end(), p.colliding.begin(), p.colliding.end(),
                      std::back_inserter(out));
  return out;
}

std::string layer_name(std::size_t k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "layer%02zu", k);
  return buf;
}

namespace {

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

std::string sanitize(const std::string& name) {
  std::string s;
  for (char c : name) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  return s.empty() ? "object" : s;
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

}  // namespace

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
    const bool layer_scripts = previews && !viewer_embeds_layers(d);  // the viewer's data, a file a layer
    std::size_t view_index = 0;
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
      if (!p.missed.empty()) {
        std::string missed;
        for (const DumpPair::Missed& m : p.missed)
          missed += std::to_string(m.tri_a) + " " + std::to_string(m.tri_b) + " " + m.verdict + ": " + m.why + "\n";
        write_text(tmp / p.dir / "missed.txt", missed);
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
          if (layer_scripts)
            write_text(tmp / v.dir / (layer_name(k) + ".js"), viewer_layer_script(view_index, k, v.layers[k]));
        }
        ++view_index;
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

// missed.txt: "triA triB verdict: why" per line.
std::vector<DumpPair::Missed> parse_missed(const fs::path& path) {
  std::istringstream in(read_text(path));
  std::vector<DumpPair::Missed> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream l(line);
    DumpPair::Missed m;
    std::string verdict;
    if (!(l >> m.tri_a >> m.tri_b >> verdict) || verdict.size() < 2 || verdict.back() != ':')
      throw InputError("peelcd: '" + path.string() + "': malformed line \"" + line +
                       "\" (expected \"triA triB verdict: why\")");
    m.verdict = verdict.substr(0, verdict.size() - 1);
    std::getline(l >> std::ws, m.why);
    out.push_back(std::move(m));
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
      if (fs::exists(root / p.dir / "missed.txt")) p.missed = parse_missed(root / p.dir / "missed.txt");
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

}  // namespace peelcd::oracle
