#include "peelcd/oracle/viewer.h"

#include <sstream>

namespace peelcd::oracle {
namespace {

std::string base64(const std::vector<std::uint8_t>& bytes) {
  static const char* const k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t b0 = bytes[i], b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0,
                        b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const std::uint32_t w = b0 << 16 | b1 << 8 | b2;
    out += k[w >> 18 & 63];
    out += k[w >> 12 & 63];
    out += i + 1 < bytes.size() ? k[w >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? k[w & 63] : '=';
  }
  return out;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace

std::string viewer_html(const Dump& d) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>peelcd layer dump</title>\n"
    << "<style>body{font-family:sans-serif;background:#15151c;color:#ddd;margin:1em}"
       "h2{margin-top:1.5em}table{border-collapse:collapse}td,th{border:1px solid #444;padding:2px 6px;"
       "font-size:12px}.layers{display:flex;flex-wrap:wrap;gap:10px}figure{margin:0}"
       "figcaption{font-size:12px}img{image-rendering:pixelated;width:512px;border:1px solid #333}"
       ".pcs{color:#f0f}.meta{font-size:13px;color:#aaa}</style>\n"
    << "<script>\nwindow.peelcdErrors=[];\n"
       "window.addEventListener('error',function(e){window.peelcdErrors.push(String(e.message||e.type));},true);\n"
       "(function(){var ce=console.error;console.error=function(){window.peelcdErrors.push("
       "Array.prototype.join.call(arguments,' '));ce.apply(console,arguments);};})();\n"
       "window.addEventListener('load',function(){\n"
       "  var imgs=document.querySelectorAll('img.layer'),bad=[];\n"
       "  imgs.forEach(function(i){if(!i.complete||i.naturalWidth===0)bad.push(i.alt);});\n"
       "  var s=document.getElementById('status');\n"
       "  var ok=bad.length===0&&window.peelcdErrors.length===0;\n"
       "  s.setAttribute('data-status',ok?'ok':'error');\n"
       "  s.textContent=(ok?'viewer ok: ':'viewer error: ')+imgs.length+' layer images loaded'+"
       "(bad.length?', not loaded: '+bad.join(', '):'')+(window.peelcdErrors.length?', errors: '+"
       "window.peelcdErrors.join('; '):'');\n"
       "});\n</script></head><body>\n";
  h << "<h1>peelcd layer dump</h1>\n<p class=\"meta\">" << escape(d.renderer) << " &middot; "
    << escape(d.gl_version) << " &middot; backend " << escape(d.backend) << " &middot; shaders "
    << escape(d.shader_hash) << "<br>options " << escape(d.options.dump()) << "</p>\n";
  h << "<p id=\"status\" data-status=\"pending\">viewer: loading</p>\n";
  h << "<p>Each layer: depth (grey, near = bright) | triangle IDs (object A warm, B cool). "
       "<span class=\"pcs\">Magenta</span> texels: this layer took part in a PCS by the test the stage used, "
       "recomputed from the layers: point sampling, this layer and the one before are of different objects and "
       "within epsilon; conservative, this layer's depth interval overlaps one of the other object's at the "
       "texel.</p>\n";
  if (d.pairs.empty()) h << "<p>No overlapping bounding boxes: nothing was peeled.</p>\n";
  for (const DumpPair& p : d.pairs) {
    h << "<h2>" << escape(p.name_a) << " (A) &times; " << escape(p.name_b) << " (B)</h2>\n";
    h << "<p>epsilon " << p.epsilon << " &middot; PCS " << p.pcs.size() << " ID pairs &middot; "
      << p.colliding.size() << " colliding triangle pairs</p>\n";
    for (const DumpView& v : p.views) {
      h << "<h3>view " << v.view << " &middot; " << v.resolution << "&sup2; &middot; " << v.layers.size()
        << " layers &middot; " << (v.a_first ? "A" : "B") << " peeled first &middot; view PCS "
        << v.pcs.size() << "</h3>\n<div class=\"layers\">\n";
      const std::size_t count = std::size_t(v.resolution) * v.resolution;
      for (std::size_t k = 0; k < v.layers.size(); ++k) {
        const auto marks = pcs_texels(v, k);
        std::size_t filled = 0, marked = 0, a = 0;
        for (std::size_t t = 0; t < count; ++t) {
          filled += !texel_empty(v.layers[k], t);
          a += !texel_empty(v.layers[k], t) && texel_object(v.layers[k], t) == 0;
          marked += marks[t];
        }
        const std::string alt = v.dir + " layer " + std::to_string(k);
        h << "<figure><img class=\"layer\" alt=\"" << escape(alt) << "\" src=\"data:image/png;base64,"
          << base64(encode_png(layer_preview(v.layers[k], v.resolution, marks))) << "\">"
          << "<figcaption>layer " << k << ": " << filled << " texels (" << a << " A, " << filled - a
          << " B), <span class=\"pcs\">" << marked << " PCS texels</span></figcaption></figure>\n";
      }
      h << "</div>\n";
    }
    h << "<details><summary>colliding pairs (" << p.colliding.size()
      << ")</summary><table><tr><th>triangle of A</th><th>triangle of B</th><th>kind</th></tr>\n";
    for (std::size_t i = 0; i < p.colliding.size(); ++i)
      h << "<tr><td>" << p.colliding[i][0] << "</td><td>" << p.colliding[i][1] << "</td><td>"
        << escape(p.kinds[i]) << "</td></tr>\n";
    h << "</table></details>\n";
  }
  h << "</body></html>\n";
  return h.str();
}

}  // namespace peelcd::oracle
