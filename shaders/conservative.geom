#version 450 core
// Conservative mode, step 1: each triangle becomes the quad of its window-space bounding box
// grown by half a texel and its error margin, so that every texel its projection touches gets a
// fragment (GPU Gems 2, ch. 42, the bounding-box variant); shaders/conservative.frag then keeps
// the texels the triangle really touches. The quad lies at mid depth: nothing is clipped in
// depth, the fragment computes the triangle's depth interval itself.
// The arithmetic is shaders/conservative.inc's (cover_triangle()), shared with the compute path.
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

#include "conservative.inc"  // cover_triangle()

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
  vec3 wx, wy, wz;
  vec2 margin, lo, hi;
  if (!cover_triangle(vec3[3](v_local[0], v_local[1], v_local[2]), vec3[3](v_mag[0], v_mag[1], v_mag[2]),
                      clip_from_local, n, grow_texels, grow_depth, wx, wy, wz, margin, lo, hi))
    return;
  vec2 ndc_lo = lo * (2.0 / w) - 1.0, ndc_hi = hi * (2.0 / w) - 1.0;
  vec2 corners[4] = vec2[4](ndc_lo, vec2(ndc_hi.x, ndc_lo.y), vec2(ndc_lo.x, ndc_hi.y), ndc_hi);
  for (int k = 0; k < 4; ++k) {
    g_x = wx;
    g_y = wy;
    g_z = wz;
    g_margin = margin;
    g_order = v_order[0];
#ifdef PEELCD_BATCH
    g_view = v_view[0];
#endif
    gl_Position = vec4(corners[k], 0.0, 1.0);
    EmitVertex();
  }
  EndPrimitive();
}
