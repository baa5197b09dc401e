#include "peelcd/oracle/viewer.h"
#include "text_file.h"

#include <algorithm>
#include <iterator>
#include <sstream>

namespace peelcd::oracle {

std::string base64_bytes(const std::vector<std::uint8_t>& bytes) {
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

namespace {

std::string base64(const std::vector<std::uint8_t>& bytes) { return base64_bytes(bytes); }

// The page's script: the status self-check (every layer image decoded, no script error, a texel
// read back), the per-texel readout on hover and click, the search of a triangle or an ID pair,
// the colliding-only filter. Texel words come from `peelcdViews` (base64 of each layer's
// little-endian 32-bit words, GL rows bottom first), where the dump was small enough to embed.
const char* const kViewerScript = R"JS(
window.peelcdErrors=[];
window.addEventListener('error',function(e){window.peelcdErrors.push(String(e.message||e.type));},true);
(function(){var ce=console.error;console.error=function(){window.peelcdErrors.push(Array.prototype.join.call(arguments,' '));ce.apply(console,arguments);};})();
var peelcdWords={},peelcdPending={};
// A large dump's layers come one file each (DIR/<view>/layerKK.js, loaded by a script tag when
// first needed: file:// pages may load scripts, not fetch files); need() runs `then` once layer
// k of view v is at hand.
function layerName(k){return 'layer'+(k<10?'0':'')+k;}
function peelcdLayerLoaded(v,k,b64){var V=peelcdViews[v];if(!V.layers)V.layers=[];V.layers[k]=b64;
  var cbs=peelcdPending[v+'/'+k]||[];delete peelcdPending[v+'/'+k];cbs.forEach(function(f){f();});}
function need(v,k,then){var V=peelcdViews[v];if(!V.external||(V.layers&&V.layers[k])){then();return;}
  var key=v+'/'+k;if(peelcdPending[key]){peelcdPending[key].push(then);return;}peelcdPending[key]=[then];
  var s=document.createElement('script');s.src=V.dir+'/'+layerName(k)+'.js';
  s.onerror=function(){window.peelcdErrors.push('layer data not found: '+s.src);};document.head.appendChild(s);}
function words(v,k){var key=v+'/'+k;if(peelcdWords[key])return peelcdWords[key];var V=peelcdViews[v];if(!V||!V.layers||!V.layers[k])return null;
  var bin=atob(V.layers[k]),u8=new Uint8Array(bin.length);for(var i=0;i<bin.length;++i)u8[i]=bin.charCodeAt(i);
  return peelcdWords[key]=new Uint32Array(u8.buffer);}
function f32(w){var b=new ArrayBuffer(4);new Uint32Array(b)[0]=w;return new Float32Array(b)[0];}
// The texel (x, y from the top) of layer k of view v, in words.
function texelText(v,k,x,y){var V=peelcdViews[v],n=V.n,W=words(v,k);
  if(!W)return V.dir+' layer '+k+' texel ('+x+', '+y+'): '+(V.external?'loading the layer':'no texel data');
  var t=((n-1-y)*n+x)*4,id1=W[t+1]&0x7fffffff,obj=W[t+1]>>>31;
  var s=V.dir+' layer '+k+' texel ('+x+', '+y+'): ';
  if(id1===0)return s+'empty';
  s+=(obj?'B':'A')+' ID '+(id1-1)+', depth '+f32(W[t]).toPrecision(9);
  if(V.conservative)s+=' .. '+f32(W[t+2]).toPrecision(9);
  else s+=', dz/dx '+f32(W[t+2]).toPrecision(4)+', dz/dy '+f32(W[t+3]).toPrecision(4);
  return s;}
function readout(img,e,pin){var v=+img.dataset.view,k=+img.dataset.layer,n=peelcdViews[v].n;
  // The preview is depth | IDs side by side (2n x n): either half reads the same texel.
  var x=Math.min(2*n-1,Math.floor(e.offsetX*2*n/img.clientWidth))%n,y=Math.min(n-1,Math.floor(e.offsetY*n/img.clientHeight));
  var r=document.getElementById('readout');r.dataset.pinned=pin?'1':'';
  var show=function(){if(!r.dataset.pinned||pin)r.textContent=texelText(v,k,x,y)+(pin?' (pinned)':'');};show();need(v,k,show);}
// Search: a triangle index ("12", "a:12", "b:34") or a triangle pair ("12,34"): the colliding
// and missed pairs that hold it are shown, the others hidden (a missed pair with why it was
// missed); texels of that ID are outlined on the layers.
// done() runs once the search's drawing is complete (a pair's layers loaded and marked).
function search(q,done){q=q.trim().toLowerCase();var side=null,m;done=done||function(){};
  if((m=/^([ab]):(\d+)$/.exec(q))){side=m[1];q=m[2];}
  var pair=/^(\d+)\s*,\s*(\d+)$/.exec(q),hits=0,missed=0,why='',rows=[];
  document.querySelectorAll('tr.pair').forEach(function(tr){var a=tr.dataset.a,b=tr.dataset.b;
    var hit=q===''||(pair?(a===pair[1]&&b===pair[2]):((side!=='b'&&a===q)||(side!=='a'&&b===q)));
    tr.style.display=hit?'':'none';if(!hit||q==='')return;
    if(pair&&tr.dataset.ia!==undefined)rows.push(tr);
    if(tr.classList.contains('missed')){missed++;if(pair)why=tr.dataset.why||'not explained in this dump';}else hits++;});
  document.querySelectorAll('canvas.mark').forEach(function(c){var g=c.getContext('2d');g.clearRect(0,0,c.width,c.height);
    if(q===''||pair)return;var v=+c.dataset.view,k=+c.dataset.layer;need(v,k,function(){outline(c,g,v,k,q,side);});});
  var text=q===''?'':hits+' colliding pairs hold it';

  if(q!==''&&missed)text+='; '+(pair?'missed: '+why:missed+' missed pairs hold it');
  else if(q!==''&&pair&&!hits&&document.querySelector('section.roi[data-reference]'))text+='; not a pair of the exact reference (the triangles do not meet)';
  document.getElementById('hits').textContent=text;
  document.querySelectorAll('details.pairs').forEach(function(d){if(q!=='')d.open=true;});
  if(!rows.length){done();return;}
  pairCoverage(rows,function(t){document.getElementById('hits').textContent=text+'; in the layers: '+t;done();});}
// A searched pair's two triangles in the layers of each ROI whose table holds it, by the IDs they
// write (its row's data-ia, data-ib): A's texels green, B's cyan, white where the two meet in
// depth (conservative: their depth intervals overlap; point sampled: within the view's epsilon).
function pairCoverage(rows,done){var jobs=[];
  rows.forEach(function(tr){var sec=tr.closest('section.roi');if(!sec)return;
    sec.querySelectorAll('canvas.mark').forEach(function(c){jobs.push({c:c,ia:+tr.dataset.ia,ib:+tr.dataset.ib,v:+c.dataset.view,k:+c.dataset.layer});});});
  var left=jobs.length;if(!left){done('no layers');return;}
  jobs.forEach(function(j){need(j.v,j.k,function(){if(--left===0)mark();});});
  function mark(){var views={},na=0,nb=0,nm=0;jobs.forEach(function(j){(views[j.v]=views[j.v]||[]).push(j);});
    Object.keys(views).forEach(function(v){var js=views[v],V=peelcdViews[v],n=V.n,ia=js[0].ia,ib=js[0].ib;
      var Ws=js.map(function(j){return words(j.v,j.k);}),meet=new Uint8Array(n*n);
      for(var t=0;t<n*n;++t){var A=[],B=[];
        for(var l=0;l<Ws.length;++l){var W=Ws[l];if(!W)continue;var w1=W[4*t+1],id1=w1&0x7fffffff;if(id1===0)continue;
          var lo=f32(W[4*t]),hi=V.conservative?f32(W[4*t+2]):lo;
          if((w1>>>31)===0&&id1-1===ia)A.push([lo,hi]);else if((w1>>>31)===1&&id1-1===ib)B.push([lo,hi]);}
        if(A.length)na++;if(B.length)nb++;
        for(var i=0;i<A.length&&!meet[t];++i)for(var j=0;j<B.length;++j){var a=A[i],b=B[j];
          if(V.conservative?(a[0]<=b[1]&&b[0]<=a[1]):Math.abs(a[0]-b[0])<=V.eps){meet[t]=1;nm++;break;}}}
      js.forEach(function(j,l){var W=Ws[l],c=j.c,g=c.getContext('2d');g.clearRect(0,0,c.width,c.height);if(!W)return;
        var w=Math.max(1,c.width/(2*n)),hh=Math.max(1,c.height/n);
        for(var t=0;t<n*n;++t){var w1=W[4*t+1],id1=w1&0x7fffffff,mine=meet[t]?'rgba(255,255,255,0.95)':
            id1!==0&&(w1>>>31)===0&&id1-1===ia?'rgba(0,255,0,0.8)':id1!==0&&(w1>>>31)===1&&id1-1===ib?'rgba(0,220,255,0.8)':null;
          if(!mine)continue;var x=t%n,y=n-1-Math.floor(t/n);g.fillStyle=mine;
          g.fillRect(x*c.width/(2*n),y*hh,w,hh);g.fillRect((x+n)*c.width/(2*n),y*hh,w,hh);}});});
    done("A's triangle (ID "+jobs[0].ia+') in '+na+" texels, B's (ID "+jobs[0].ib+') in '+nb+', meeting in depth at '+nm);}}
// The texels of ID q (of A, B or either) outlined on layer k of view v's canvas.
function outline(c,g,v,k,q,side){var n=peelcdViews[v].n,W=words(v,k);if(!W||document.getElementById('q').value.trim().toLowerCase().replace(/^[ab]:/,'')!==q)return;
  g.fillStyle='rgba(0,255,0,0.8)';for(var t=0;t<n*n;++t){var id1=W[4*t+1]&0x7fffffff,obj=W[4*t+1]>>>31;
    if(id1===0||String(id1-1)!==q||(side==='a'&&obj)||(side==='b'&&!obj))continue;
    var x=t%n,y=n-1-Math.floor(t/n),w=Math.max(1,c.width/(2*n)),hh=Math.max(1,c.height/n);
    g.fillRect(x*c.width/(2*n),y*hh,w,hh);g.fillRect((x+n)*c.width/(2*n),y*hh,w,hh);}}
function collidingOnly(on){document.querySelectorAll('section.roi').forEach(function(s){s.style.display=on&&s.dataset.colliding==='0'?'none':'';});}
window.addEventListener('load',function(){
  var imgs=document.querySelectorAll('img.layer'),bad=[];
  imgs.forEach(function(i){if(!i.complete||i.naturalWidth===0)bad.push(i.alt);
    i.addEventListener('mousemove',function(e){if(!document.getElementById('readout').dataset.pinned)readout(i,e,false);});
    i.addEventListener('click',function(e){readout(i,e,true);});});
  // #search=Q in the address: the search run on load, its hits in the status (and a test's).
  var m=/search=([^&]+)/.exec(location.hash),searched='';
  // Self-check: the first layer's first non-empty texel read back through the readout (its data
  // loaded first in a large dump: the time that took is in the status).
  var selfCheck=function(){
  var finish=function(check,ms){var s=document.getElementById('status');
    var ok=imgs.length>0&&bad.length===0&&window.peelcdErrors.length===0&&check==='readout ok';
    s.setAttribute('data-status',ok?'ok':'error');
    s.textContent=(ok?'viewer ok: ':'viewer error: ')+imgs.length+' layer images loaded, '+check+
      (ms!==null?' (layer data loaded in '+ms+' ms)':'')+searched+(bad.length?', not loaded: '+bad.join(', '):'')+
      (window.peelcdErrors.length?', errors: '+window.peelcdErrors.join('; '):'');};
  if(!imgs.length){finish('no layer',null);return;}
  var v=+imgs[0].dataset.view,t0=performance.now();
  need(v,0,function(){var n=peelcdViews[v].n,W=words(v,0),check='readout: no texel data';
    if(W)for(var t=0;t<n*n;++t)if((W[4*t+1]&0x7fffffff)!==0){var txt=texelText(v,0,t%n,n-1-Math.floor(t/n));
      check=/ ID \d+, depth /.test(txt)?'readout ok':'readout wrong: '+txt;break;}
    finish(check,peelcdViews[v].external?Math.round(performance.now()-t0):null);});};
  if(m){var q=decodeURIComponent(m[1]);document.getElementById('q').value=q;
    search(q,function(){searched=', search "'+q+'": '+document.getElementById('hits').textContent;selfCheck();});}
  else selfCheck();
});
)JS";

// Texel words embedded up to this many bytes per dump (base64 adds a third): beyond, one file a
// layer beside its preview, loaded by the page when first needed (viewer_layer_script()).
constexpr std::size_t kEmbedBytes = 24u << 20;


// A pair row's data-ia, data-ib: the IDs its triangles write, where the dump knows them.
std::string row_ids(const DumpPair& p, std::uint32_t ta, std::uint32_t tb) {
  const auto a = p.ids_a.find(ta), b = p.ids_b.find(tb);
  if (a == p.ids_a.end() || b == p.ids_b.end()) return "";
  return " data-ia=\"" + std::to_string(a->second) + "\" data-ib=\"" + std::to_string(b->second) + "\"";
}

}  // namespace

std::string layer_base64(const std::vector<std::uint32_t>& layer) {
  std::vector<std::uint8_t> bytes(layer.size() * 4);
  for (std::size_t i = 0; i < layer.size(); ++i)
    for (int b = 0; b < 4; ++b) bytes[4 * i + std::size_t(b)] = std::uint8_t(layer[i] >> (8 * b));
  return base64_bytes(bytes);
}

bool viewer_embeds_layers(const Dump& d) {
  std::size_t bytes = 0;
  for (const DumpPair& p : d.pairs)
    for (const DumpView& v : p.views)
      for (const auto& layer : v.layers) bytes += layer.size() * 4;
  return bytes <= kEmbedBytes;
}

std::string viewer_layer_script(std::size_t view_index, std::size_t k, const std::vector<std::uint32_t>& layer) {
  return "peelcdLayerLoaded(" + std::to_string(view_index) + "," + std::to_string(k) + ",\"" + layer_base64(layer) +
         "\");\n";
}

namespace {

// One ROI's section of the page: its views' layers (view_index counts the page's views), its
// missed pairs (with a reference) and its colliding pairs.
void write_roi_section(std::ostringstream& h, const DumpPair& p, std::size_t& view_index) {
  h << "<section class=\"roi\" data-colliding=\"" << p.colliding.size() << "\""
    << (p.has_reference ? " data-reference=\"1\"" : "") << " id=\"" << html_escape(p.dir) << "\">\n";
  h << "<h2>" << html_escape(p.name_a) << " (A) &times; " << html_escape(p.name_b) << " (B)</h2>\n";
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
      // The preview is depth | IDs side by side (2n x n texels on 512 x 256 pixels); the canvas
      // over it takes the search's outlines.
      h << "<figure><img class=\"layer\" data-view=\"" << view_index << "\" data-layer=\"" << k << "\" alt=\""
        << html_escape(alt) << "\" src=\"data:image/png;base64,"
        << base64(encode_png(layer_preview(v.layers[k], v.resolution, marks))) << "\">"
        << "<canvas class=\"mark\" data-view=\"" << view_index << "\" data-layer=\"" << k
        << "\" width=\"512\" height=\"256\"></canvas>"
        << "<figcaption>layer " << k << ": " << filled << " texels (" << a << " A, " << filled - a
        << " B), <span class=\"pcs\">" << marked << " PCS texels</span></figcaption></figure>\n";
    }
    h << "</div>\n";
    ++view_index;
  }
  if (p.has_reference) {
    // The missed pairs first in line for debugging: each with why (peelcd explain's verdict on
    // the same frame, where the dump holds it) and the command that shows it texel by texel.
    const auto missed = missed_pairs(p);
    h << "<details class=\"pairs\"" << (missed.empty() ? "" : " open") << "><summary>missed pairs (" << missed.size()
      << " of " << p.reference.size() << " exact pairs)</summary><table><tr><th>triangle of A</th><th>triangle of B"
         "</th><th>why missed (peelcd explain)</th><th>explain</th></tr>\n";
    for (const auto& m : missed) {
      const DumpPair::Missed* why = nullptr;
      for (const DumpPair::Missed& x : p.missed)
        if (x.tri_a == m[0] && x.tri_b == m[1]) why = &x;
      const std::string line = why ? why->verdict + ": " + why->why : "";
      h << "<tr class=\"pair missed\" data-a=\"" << m[0] << "\" data-b=\"" << m[1] << "\" data-why=\"" << html_escape(line)
        << "\"" << row_ids(p, m[0], m[1]) << "><td>" << m[0] << "</td><td>" << m[1] << "</td><td>"
        << (why ? "<b>" + html_escape(why->verdict) + "</b> " + html_escape(why->why) : std::string("(not explained in this dump)"))
        << "</td><td><code>peelcd explain SCENE --pair " << html_escape(p.name_a) << ":" << m[0] << "," << html_escape(p.name_b)
        << ":" << m[1] << " --out DIR</code></td></tr>\n";
    }
    h << "</table></details>\n";
  }
  h << "<details class=\"pairs\"><summary>colliding pairs (" << p.colliding.size()
    << ")</summary><table><tr><th>triangle of A</th><th>triangle of B</th><th>kind</th><th>explain</th></tr>\n";
  for (std::size_t i = 0; i < p.colliding.size(); ++i)
    h << "<tr class=\"pair\" data-a=\"" << p.colliding[i][0] << "\" data-b=\"" << p.colliding[i][1] << "\""
      << row_ids(p, p.colliding[i][0], p.colliding[i][1]) << "><td>"
      << p.colliding[i][0] << "</td><td>" << p.colliding[i][1] << "</td><td>" << html_escape(p.kinds[i])
      << "</td><td><code>peelcd explain SCENE --pair " << html_escape(p.name_a) << ":" << p.colliding[i][0] << ","
      << html_escape(p.name_b) << ":" << p.colliding[i][1] << "</code></td></tr>\n";
  h << "</table></details>\n";
  h << "</section>\n";
}

}  // namespace

std::string viewer_html(const Dump& d) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>peelcd layer dump</title>\n"
    << "<style>body{font-family:sans-serif;background:#15151c;color:#ddd;margin:1em}"
       "h2{margin-top:1.5em}table{border-collapse:collapse}td,th{border:1px solid #444;padding:2px 6px;"
       "font-size:12px}.layers{display:flex;flex-wrap:wrap;gap:10px}figure{margin:0;position:relative}"
       "figcaption{font-size:12px}img{image-rendering:pixelated;width:512px;border:1px solid #333;cursor:crosshair}"
       "canvas.mark{position:absolute;left:1px;top:1px;pointer-events:none}"
       ".pcs{color:#f0f}.meta{font-size:13px;color:#aaa}#tools{position:sticky;top:0;background:#15151c;"
       "padding:6px 0;border-bottom:1px solid #444;z-index:2}#readout{font-family:monospace;color:#9f9}"
       "code{color:#fc6}a{color:#8cf}</style>\n";
  // The views' texel words, for the readout and the search: in the page, or one file a layer.
  const bool embed = viewer_embeds_layers(d);
  h << "<script>\nvar peelcdViews=[";
  std::size_t view_index = 0;
  for (const DumpPair& p : d.pairs)
    for (const DumpView& v : p.views) {
      h << (view_index++ ? ",\n" : "\n") << "{dir:\"" << html_escape(v.dir) << "\",n:" << v.resolution
        << ",conservative:" << (v.conservative ? "true" : "false") << ",eps:" << v.epsilon_window;
      if (embed) {
        h << ",layers:[";
        for (std::size_t k = 0; k < v.layers.size(); ++k) h << (k ? "," : "") << "\"" << layer_base64(v.layers[k]) << "\"";
        h << "]";
      } else {
        h << ",external:true";
      }
      h << "}";
    }
  h << "];\n" << kViewerScript << "</script></head><body>\n";
  h << "<h1>peelcd layer dump</h1>\n<p class=\"meta\">" << html_escape(d.renderer) << " &middot; "
    << html_escape(d.gl_version) << " &middot; backend " << html_escape(d.backend) << " &middot; shaders "
    << html_escape(d.shader_hash) << "<br>options " << html_escape(d.options.dump());
  if (!d.gl_options.is_null()) h << "<br>GL stage " << html_escape(d.gl_options.dump());
  h << "</p>\n";
  h << "<p id=\"status\" data-status=\"pending\">viewer: loading</p>\n";
  // The tools: readout, search, filter.
  h << "<div id=\"tools\">Search <input id=\"q\" size=\"14\" placeholder=\"12, a:12, b:34, 12,34\" "
       "oninput=\"search(this.value)\"> <span id=\"hits\"></span> &middot; <label><input type=\"checkbox\" "
       "onchange=\"collidingOnly(this.checked)\"> colliding pairs only</label><br>"
       "<span id=\"readout\">hover a layer for its texel; click to pin</span></div>\n";
  h << "<p>Each layer: depth (grey, near = bright) | triangle IDs (object A warm, B cool). "
       "<span class=\"pcs\">Magenta</span> texels: this layer took part in a PCS by the test the stage used, "
       "recomputed from the layers: point sampling, this layer and the one before are of different objects and "
       "within epsilon; conservative, this layer's depth interval overlaps one of the other object's at the "
       "texel. The search outlines the texels of a triangle's ID in green (with unique IDs, the triangle).";
  if (!embed)
    h << " The texel words (over " << (kEmbedBytes >> 20)
      << " MB in all) are one file a layer beside its preview, loaded when a layer is first hovered or searched.";
  h << "</p>\n";
  if (d.pairs.empty()) h << "<p>No overlapping bounding boxes: nothing was peeled.</p>\n";
  // The index: every ROI pair, its views and counts, linked.
  if (!d.pairs.empty()) {
    h << "<h2>Index</h2>\n<table><tr><th>pair</th><th>views</th><th>layers</th><th>PCS</th><th>colliding</th>"
         "<th>missed (of the exact reference)</th></tr>\n";
    for (const DumpPair& p : d.pairs) {
      std::size_t layers = 0;
      for (const DumpView& v : p.views) layers += v.layers.size();
      h << "<tr><td><a href=\"#" << html_escape(p.dir) << "\">" << html_escape(p.name_a) << " &times; " << html_escape(p.name_b)
        << "</a></td><td>" << p.views.size() << "</td><td>" << layers << "</td><td>" << p.pcs.size() << "</td><td>"
        << p.colliding.size() << "</td><td>";
      if (p.has_reference)
        h << missed_pairs(p).size() << " of " << p.reference.size();
      else
        h << "-";
      h << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  view_index = 0;
  for (const DumpPair& p : d.pairs) write_roi_section(h, p, view_index);
  h << "</body></html>\n";
  return h.str();
}

}  // namespace peelcd::oracle
