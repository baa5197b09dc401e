#version 450 core
// One peel pass: triangles of one object in ROI-local coordinates (double on the CPU, float
// here), projected orthographically along the view direction and clipped to the ROI box.
// PEELCD_BATCH (point-sampled views batched, gl/batch.cpp): every view of a frame in one indirect
// draw. Triangle k of the draw is entries[k] (shaders/batch.inc); the view's matrices and ROI box
// come from the views buffer. Window coordinates are the view's own (texel i at [i, i + 1)) in a
// viewport of `viewport` texels (the batch's largest view): a view of that size is drawn exactly
// as the one-view draw draws it; shaders/abuffer.frag maps the texel into the view's part of the
// packed k-buffer.
#ifdef PEELCD_BATCH
#define PEELCD_BATCH_DRAW
#include "batch.inc"  // the views, the entries, batch_corner()
uniform int viewport;
flat out uint v_view;  // view << 1 | object
#else
layout(location = 0) in vec3 in_position;  // ROI-local, world units (or a rigid shape's local)
layout(location = 1) in uint id;        // triangle ID of this corner (unique or paper, see core/image/id_map.h)

uniform mat4 clip_from_local;
uniform mat4 roi_from_object;  // identity, or a rigid object's pose (ROI-local from its shape)
uniform vec3 box_lo;  // ROI box, ROI-local
uniform vec3 box_hi;
flat out uint v_id;  // flat: the last (provoking) vertex decides the fragment's ID
#endif

// The triangle's place in the draw order (single-pass peeling breaks depth ties with it):
// corners are drawn three per triangle in order, as arrays or by indices 3t + k in ascending t.
flat out uint v_order;
out float gl_ClipDistance[6];

void main() {
#ifdef PEELCD_BATCH
  vec3 in_position = batch_corner(v_view);
  uint view = v_view >> 1;
  mat4 roi_from_object = views[view].roi_from_object[v_view & 1u];
  mat4 clip_from_local = views[view].clip_from_local;
  vec3 box_lo = views[view].box_lo.xyz, box_hi = views[view].box_hi.xyz;
#endif
  vec3 p = (roi_from_object * vec4(in_position, 1.0)).xyz;
  gl_Position = clip_from_local * vec4(p, 1.0);
#ifdef PEELCD_BATCH
  int n = views[view].info.x;
  if (n != viewport) gl_Position.xy = (gl_Position.xy + gl_Position.w) * (float(n) / float(viewport)) - gl_Position.w;
#else
  v_id = id;
#endif
  gl_ClipDistance[0] = p.x - box_lo.x;
  gl_ClipDistance[1] = box_hi.x - p.x;
  gl_ClipDistance[2] = p.y - box_lo.y;
  gl_ClipDistance[3] = box_hi.y - p.y;
  gl_ClipDistance[4] = p.z - box_lo.z;
  gl_ClipDistance[5] = box_hi.z - p.z;
  v_order = uint(gl_VertexID) / 3u;
}
