#version 450 core
// Conservative mode, step 1: each triangle becomes the quad of its window-space bounding box
// grown by half a texel and its error margin, so that every texel its projection touches gets a
// fragment (GPU Gems 2, ch. 42, the bounding-box variant); shaders/conservative.frag then keeps
// the texels the triangle really touches. The quad lies at mid depth: nothing is clipped in
// depth, the fragment computes the triangle's depth interval itself.
// The arithmetic and the constants are peelcd/core/image/conservative.h's.
//
// PEELCD_BATCH (shaders/conservative.vert): the view's matrix and resolution come from the views
// buffer; window coordinates are the view's own (texel i of the view at [i, i + 1)), the quad is
// placed in a viewport of `viewport` texels (the largest view of the batch), and the fragment
// shader maps the texel into the view's part of the packed k-buffer.
layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

in vec3 v_local[];
in vec3 v_mag[];
flat in uint v_order[];

#ifdef PEELCD_BATCH
flat in uint v_view[];
#include "batch.inc"  // the views
uniform int viewport;
flat out uint g_view;
#else
uniform mat4 clip_from_local;
uniform int resolution;
uniform float grow_texels;  // proximity: every triangle grown by PeelJob::grow (texels,
uniform float grow_depth;   // window depth; 0 without a margin)
#endif

flat out vec3 g_x;       // window x of the three corners, texels
flat out vec3 g_y;       // window y
flat out vec3 g_z;       // window depth
flat out vec2 g_margin;  // error margins: texels, window depth
flat out uint g_order;

const float kVertexRel = 1.0 / 131072.0;
const float kWindowRel = 1.0 / 1048576.0;
const float kTexelAbs = 1.0 / 4096.0;
const float kDepthAbs = 1.0 / 4194304.0;

void main() {
#ifdef PEELCD_BATCH
  mat4 clip_from_local = views[v_view[0] >> 1].clip_from_local;
  float n = float(views[v_view[0] >> 1].info.x);
  float w = float(viewport);
  float grow_texels = views[v_view[0] >> 1].half_box.w;
  float grow_depth = intBitsToFloat(views[v_view[0] >> 1].info.w);
#else
  float n = float(resolution);
  float w = n;
#endif
  vec3 e = vec3(0.0);
  vec3 wx, wy, wz;
  for (int k = 0; k < 3; ++k) {
    vec4 c = clip_from_local * vec4(v_local[k], 1.0);
    wx[k] = (c.x + 1.0) * (0.5 * n);
    wy[k] = (c.y + 1.0) * (0.5 * n);
    wz[k] = 0.5 * c.z + 0.5;
    vec3 m = v_mag[k];
    e = max(e, abs(clip_from_local[0].xyz) * m.x + abs(clip_from_local[1].xyz) * m.y +
                   abs(clip_from_local[2].xyz) * m.z + abs(clip_from_local[3].xyz));
  }
  float big = max(max(max(abs(wx.x), abs(wx.y)), max(abs(wx.z), abs(wy.x))), max(abs(wy.y), abs(wy.z)));
  float mx = max(e.x, e.y) * kVertexRel * (0.5 * n) + kWindowRel * (big + n) + kTexelAbs + grow_texels;
  float mz = e.z * kVertexRel * 0.5 + kDepthAbs + grow_depth;
  // Wholly in front of or behind the ROI's depth range: no fragment can hold a contact.
  if (max(max(wz.x, wz.y), wz.z) + mz < 0.0 || min(min(wz.x, wz.y), wz.z) - mz > 1.0) return;
  float h = 0.5 + mx + 1.0 / 16.0;  // texel centres within h of the box: strictly inside the quad
  vec2 lo = vec2(min(min(wx.x, wx.y), wx.z), min(min(wy.x, wy.y), wy.z)) - h;
  vec2 hi = vec2(max(max(wx.x, wx.y), wx.z), max(max(wy.x, wy.y), wy.z)) + h;
  if (hi.x < 0.0 || hi.y < 0.0 || lo.x > n || lo.y > n) return;
  lo = max(lo, vec2(-1.0));
  hi = min(hi, vec2(n + 1.0));
  vec2 ndc_lo = lo * (2.0 / w) - 1.0, ndc_hi = hi * (2.0 / w) - 1.0;
  vec2 corners[4] = vec2[4](ndc_lo, vec2(ndc_hi.x, ndc_lo.y), vec2(ndc_lo.x, ndc_hi.y), ndc_hi);
  for (int k = 0; k < 4; ++k) {
    g_x = wx;
    g_y = wy;
    g_z = wz;
    g_margin = vec2(mx, mz);
    g_order = v_order[0];
#ifdef PEELCD_BATCH
    g_view = v_view[0];
#endif
    gl_Position = vec4(corners[k], 0.0, 1.0);
    EmitVertex();
  }
  EndPrimitive();
}
