// The reports of an explanation (peelcd/oracle/explain.h): JSON, text, and the page with one
// zoomed picture per view. The trace itself is explain.cpp.
#include "peelcd/oracle/explain.h"
#include "text_file.h"

#include "explain_words.h"

#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/cull.h"
#include "peelcd/core/image/id_map.h"
#include "peelcd/core/exact/narrow_phase.h"
#include "peelcd/io/error.h"
#include "peelcd/io/options_json.h"
#include "peelcd/io/output.h"
#include "peelcd/oracle/dump.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>


namespace peelcd::oracle {

namespace fs = std::filesystem;

using words::g;
using words::object_word;

nlohmann::json to_json(const Explanation& e) {
  using nlohmann::json;
  const auto vec = [](const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
  const auto pt = [](const std::array<double, 2>& p) { return json::array({p[0], p[1]}); };
  json j;
  j["schema"] = "peelcd.explain/1";
  j["pair"] = {{"object_a", e.query.object_a}, {"name_a", e.name_a}, {"tri_a", e.query.tri_a},
               {"object_b", e.query.object_b}, {"name_b", e.name_b}, {"tri_b", e.query.tri_b}};
  j["backend"] = e.backend;
  j["renderer"] = e.renderer;
  j["options"] = e.options;
  j["exact"] = {{"intersect", e.intersect}, {"kind", e.kind}};
  if (e.intersect) {
    j["exact"]["segment"] = json::array({vec(e.p), vec(e.q)});
    j["exact"]["length"] = (e.q - e.p).norm();
  }
  j["roi"] = e.roi;
  j["stage"] = e.exact_path ? "exact" : "image";
  j["predicted_ms"] = {{"exact", e.predicted_exact_ms}, {"image", e.predicted_image_ms}};
  j["culling"] = {{"kept_a", e.kept_a}, {"kept_b", e.kept_b}, {"why_a", e.cull_a}, {"why_b", e.cull_b}};
  j["ids"] = {{"a", e.id_a}, {"b", e.id_b}};
  j["candidate"] = e.candidate;
  j["reported"] = e.reported;
  if (e.depth_asked) {
    if (e.depth.known)
      j["penetration"] = {{"direction", vec(e.depth.direction)}, {"depth", e.depth.depth}, {"bound", e.depth.bound}};
    else
      j["penetration"] = {{"unknown", e.depth.reason}};
  }
  json views = json::array();
  for (const ViewReport& v : e.views) {
    json jv = {{"view", v.view},
               {"resolution", v.resolution},
               {"texel", v.texel},
               {"epsilon_window", v.epsilon_window},
               {"slope", v.slope},
               {"conservative", v.conservative},
               {"drawn_a", v.drawn_a},
               {"drawn_b", v.drawn_b},
               {"fragments_a", v.fragments_a},
               {"fragments_b", v.fragments_b},
               {"common_texels", v.common_texels},
               {"triangle_a", json::array({pt(v.window_a[0]), pt(v.window_a[1]), pt(v.window_a[2])})},
               {"triangle_b", json::array({pt(v.window_b[0]), pt(v.window_b[1]), pt(v.window_b[2])})},
               {"segment", json::array({pt(v.segment[0]), pt(v.segment[1])})},
               {"segment_texels", v.segment_texels},
               {"pcs_found", v.pcs_found},
               {"found_texels", v.found_texels},
               {"reason", to_string(v.reason)},
               {"summary", v.summary}};
    if (v.found_texels) jv["found_texel"] = json::array({v.found_x, v.found_y});
    json texels = json::array();
    for (std::size_t i = 0; i < v.texels.size(); ++i) {
      const TexelReport& r = v.texels[i];
      json layers = json::array();
      for (const TexelLayer& l : r.layers) {
        json jl = {{"layer", l.layer}, {"object", object_word(l.object)}, {"id", l.id}, {"depth", l.depth}};
        if (v.conservative) jl["depth_hi"] = l.depth_hi;
        if (l.stands_a || l.stands_b) jl["stands_for_queried"] = true;
        layers.push_back(jl);
      }
      json tests = json::array();
      for (const TexelTest& t : r.tests)
        tests.push_back({{"layer_a", t.layer_a}, {"layer_b", t.layer_b}, {"value", t.value}, {"bound", t.bound},
                         {"adjacent", t.adjacent}, {"pass", t.pass}});
      json jt = {{"texel", json::array({r.x, r.y})}, {"on_segment", i < v.segment_texel_count},
                 {"model_a", r.model_a}, {"model_b", r.model_b}, {"layers", layers}, {"tests", tests},
                 {"status", to_string(r.status)}, {"note", r.note}};
      if (r.model_a) jt["model_depth_a"] = r.model_depth_a;
      if (r.model_b) jt["model_depth_b"] = r.model_depth_b;
      texels.push_back(jt);
    }
    jv["texels"] = texels;
    views.push_back(jv);
  }
  j["views"] = views;
  j["verdict"] = to_string(e.verdict);
  j["verdict_line"] = e.verdict_line;
  return j;
}

std::string explain_text(const Explanation& e) {
  std::ostringstream s;
  const auto v3 = [](const Vec3& v) { return "(" + g(v.x()) + ", " + g(v.y()) + ", " + g(v.z()) + ")"; };
  s << "pair: A = '" << e.name_a << "' (object " << e.query.object_a << ") triangle " << e.query.tri_a << ", B = '"
    << e.name_b << "' (object " << e.query.object_b << ") triangle " << e.query.tri_b << "\n";
  s << "backend: " << e.backend << " (" << e.renderer << ")\n";
  if (e.intersect)
    s << "exact: the triangles intersect (" << e.kind << "), segment " << v3(e.p) << " - " << v3(e.q) << ", length "
      << g((e.q - e.p).norm()) << "\n";
  else
    s << "exact: the triangles do not intersect\n";
  if (!e.roi) {
    s << "ROI: the objects' boxes do not overlap\n";
  } else {
    s << "ROI: stage " << (e.exact_path ? "exact CPU path" : "image");
    if (e.options.value("stage", std::string()) == "auto")
      s << " (router: exact " << g(e.predicted_exact_ms) << " ms, image " << g(e.predicted_image_ms) << " ms predicted)\n";
    else
      s << " (not routed: --stage " << e.options.value("stage", std::string()) << ")\n";
    s << "culling: A's triangle " << (e.kept_a ? "kept" : "dropped: " + e.cull_a) << "; B's triangle "
      << (e.kept_b ? "kept" : "dropped: " + e.cull_b) << "\n";
    s << "IDs written: A " << e.id_a << ", B " << e.id_b << "; candidate: " << (e.candidate ? "yes" : "no")
      << "; reported: " << (e.reported ? "yes" : "no") << "\n";
  }
  for (const ViewReport& v : e.views) {
    s << "view " << v.view << ": " << v.resolution << "x" << v.resolution << " texels of " << g(v.texel) << " world";
    if (!v.conservative)
      s << ", epsilon " << g(v.epsilon_window) << " window depth, slope " << g(v.slope);
    else
      s << ", conservative";
    s << "\n  drawn: A " << (v.drawn_a ? "yes" : "no") << ", B " << (v.drawn_b ? "yes" : "no") << "; fragments (model): A "
      << v.fragments_a << ", B " << v.fragments_b << "; texels both cover: " << v.common_texels << "\n";
    if (e.intersect)
      s << "  segment: (" << g(v.segment[0][0]) << ", " << g(v.segment[0][1]) << ") - (" << g(v.segment[1][0]) << ", "
        << g(v.segment[1][1]) << "), " << g(v.segment_texels) << " texels long, crosses " << v.segment_texel_count
        << " texel(s)\n";
    for (std::size_t i = 0; i < v.texels.size(); ++i) {
      const TexelReport& r = v.texels[i];
      s << "  texel (" << r.x << ", " << r.y << ")" << (i < v.segment_texel_count ? " [segment]" : "") << ": model "
        << (r.model_a ? "A z=" + g(r.model_depth_a) : std::string("A -")) << ", "
        << (r.model_b ? "B z=" + g(r.model_depth_b) : std::string("B -")) << "\n    layers:";
      if (r.layers.empty()) s << " none";
      for (const TexelLayer& l : r.layers) {
        s << " " << l.layer << ":" << object_word(l.object) << "#" << l.id << "@" << g(l.depth);
        if (v.conservative) s << ".." << g(l.depth_hi);
        if (l.stands_a || l.stands_b) s << "*";
      }
      s << "\n    -> " << to_string(r.status) << ": " << r.note << "\n";
    }
    s << "  view " << v.view << ": " << to_string(v.reason) << ": " << v.summary << "\n";
  }
  if (!e.views.empty()) s << "(* = the layer's ID stands for the queried triangle)\n";
  s << "verdict: " << e.verdict_line << "\n";
  if (e.depth_asked) {
    if (e.depth.known)
      s << "depth: move '" << e.name_a << "' by " << g(e.depth.depth) << " along " << v3(e.depth.direction)
        << " to separate the objects\n";
    else
      s << "depth: unknown: " << e.depth.reason << "\n";
  }
  return s.str();
}

namespace {

// The zoomed crop of one view: layer-0 depth in grey, A's triangle's texels red, B's blue, both
// magenta, texels whose test reported the pair green; the triangles outlined, the segment yellow.
Rgb view_picture(const ViewReport& v) {
  const int w = v.crop_w, h = v.crop_h;
  const int zoom = std::clamp(480 / std::max(1, std::max(w, h)), 4, 32);
  Rgb img(w * zoom, h * zoom);
  float lo = std::numeric_limits<float>::max(), hi = -lo;
  for (const float d : v.crop_depth)
    if (!std::isnan(d)) lo = std::min(lo, d), hi = std::max(hi, d);
  const float range = hi > lo ? hi - lo : 1.0f;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const float d = v.crop_depth[i];
      const int grey = std::isnan(d) ? 24 : int(200 - 150 * (d - lo) / range);
      int r = grey, gch = grey, b = grey;
      const std::uint8_t f = v.crop_flags[i];
      if (f & 1) r = std::min(255, r / 2 + 128);
      if (f & 2) b = std::min(255, b / 2 + 128);
      if ((f & 3) == 3) gch = gch / 3;
      if (f & 4) r = 40, gch = 220, b = 60;
      for (int py = 0; py < zoom; ++py)
        for (int px = 0; px < zoom; ++px) {
          const bool grid = zoom >= 8 && (px == 0 || py == 0);
          const int yy = (h - 1 - y) * zoom + py;  // rows bottom to top
          img.set(x * zoom + px, yy,
                  {std::uint8_t(grid ? r * 3 / 4 : r), std::uint8_t(grid ? gch * 3 / 4 : gch), std::uint8_t(grid ? b * 3 / 4 : b)});
        }
      // The texel centre as a dot.
      if (zoom >= 8) img.set(x * zoom + zoom / 2, (h - 1 - y) * zoom + zoom / 2, {0, 0, 0});
    }
  const auto line = [&](std::array<double, 2> p, std::array<double, 2> q, std::array<std::uint8_t, 3> c, int thick) {
    const auto px = [&](const std::array<double, 2>& a) {
      return std::array<double, 2>{(a[0] - v.crop_x) * zoom, (v.crop_y + h - a[1]) * zoom};
    };
    const auto a = px(p), b = px(q);
    const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
    const int steps = int(std::min(1e5, std::ceil(len * 2.0))) + 1;
    for (int s = 0; s <= steps; ++s) {
      const double f = double(s) / steps;
      const int x = int(std::floor(a[0] + f * (b[0] - a[0]))), y = int(std::floor(a[1] + f * (b[1] - a[1])));
      for (int dy = 0; dy < thick; ++dy)
        for (int dx = 0; dx < thick; ++dx)
          if (x + dx >= 0 && y + dy >= 0 && x + dx < img.width && y + dy < img.height) img.set(x + dx, y + dy, c);
    }
  };
  for (int k = 0; k < 3; ++k) {
    line(v.window_a[k], v.window_a[(k + 1) % 3], {255, 60, 60}, 2);
    line(v.window_b[k], v.window_b[(k + 1) % 3], {70, 150, 255}, 2);
  }
  line(v.segment[0], v.segment[1], {255, 230, 0}, 3);
  return img;
}

}  // namespace

void write_explain_page(const Explanation& e, const std::string& dir) {
  const fs::path root(dir);
  if (fs::exists(root) && !(fs::is_directory(root) && fs::is_empty(root)))
    throw InputError("peelcd explain: --out '" + dir + "' exists and is not an empty folder");
  if (!root.parent_path().empty() && !fs::is_directory(root.parent_path()))
    throw InputError("peelcd explain: --out '" + dir + "': the parent folder does not exist");
  const fs::path tmp = root.string() + ".partial";
  DeferSignals hold;
  std::error_code ec;
  fs::remove_all(tmp, ec);
  try {
    fs::create_directories(tmp);
    std::ostringstream h;
    h << "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>peelcd explain: " << html_escape(e.name_a) << ":"
      << e.query.tri_a << " x " << html_escape(e.name_b) << ":" << e.query.tri_b << "</title>\n<style>body{font-family:sans-serif;"
      << "margin:1.5em;background:#fafafa}pre{background:#fff;border:1px solid #ccc;padding:.8em;overflow-x:auto}"
      << "figure{display:inline-block;margin:0 1.5em 1.5em 0;vertical-align:top}img{image-rendering:pixelated;"
      << "border:1px solid #888}.verdict{font-size:1.2em;font-weight:bold}</style></head><body>\n";
    h << "<h1>peelcd explain</h1>\n<p class=\"verdict\">" << html_escape(e.verdict_line) << "</p>\n";
    h << "<p>Pictures: layer 0's depth in grey (near = light), the texels A's triangle covers alone (the rasterization "
         "model) tinted red, B's blue, both magenta; texels where the pair's test passed green; A's triangle outlined "
         "red, B's blue, the intersection segment yellow; black dots are texel centres.</p>\n";
    for (const ViewReport& v : e.views) {
      const std::string name = "view" + std::to_string(v.view) + ".png";
      write_png((tmp / name).string(), view_picture(v));
      h << "<figure><img src=\"" << name << "\" alt=\"view " << v.view << "\"><figcaption>view " << v.view << ": texels ("
        << v.crop_x << ".." << v.crop_x + v.crop_w - 1 << ", " << v.crop_y << ".." << v.crop_y + v.crop_h - 1 << ") of "
        << v.resolution << "&sup2;<br>" << html_escape(to_string(v.reason)) << ": " << html_escape(v.summary)
        << "</figcaption></figure>\n";
    }
    h << "<h2>Report</h2>\n<pre>" << html_escape(explain_text(e)) << "</pre>\n</body></html>\n";
    std::ofstream(tmp / "index.html") << h.str();
    std::ofstream(tmp / "explain.json") << to_json(e).dump(2) << "\n";
    if (fs::exists(root)) fs::remove(root);
    fs::rename(tmp, root);
  } catch (const fs::filesystem_error& err) {
    fs::remove_all(tmp, ec);
    throw InputError("peelcd explain: --out '" + dir + "': " + err.what());
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

}  // namespace peelcd::oracle
