#version 450 core
// Conservative mode, batched: every ROI view of a frame in one draw (GlImageStage::peel_batch).
// As shaders/conservative.vert, but each triangle's view and object (A or B) come from a buffer,
// and its corners are shape-local (a rigid object) or ROI-local, moved by its view's matrix.
layout(location = 0) in vec3 in_position;
layout(location = 1) in uint id;  // unused: the resolve reads IDs by draw order

struct BatchView {
  mat4 clip_from_local;
  mat4 roi_from_object[2];  // per object: identity, or a rigid object's pose (ROI-local)
  ivec4 info;               // resolution, first texel in the packed k-buffer, -, -
};
layout(std430, binding = 3) readonly buffer Views { BatchView views[]; };
layout(std430, binding = 4) readonly buffer Triangles { uint triangle_view[]; };  // view << 1 | object

out vec3 v_local;
out vec3 v_mag;
flat out uint v_order;  // the triangle's place in the draw order (all views)
flat out uint v_view;   // view << 1 | object

void main() {
  uint order = uint(gl_VertexID) / 3u;
  uint info = triangle_view[order];
  mat4 roi_from_object = views[info >> 1].roi_from_object[info & 1u];
  v_local = (roi_from_object * vec4(in_position, 1.0)).xyz;
  vec3 a = abs(in_position);
  v_mag = abs(roi_from_object[0].xyz) * a.x + abs(roi_from_object[1].xyz) * a.y +
          abs(roi_from_object[2].xyz) * a.z + abs(roi_from_object[3].xyz);
  v_order = order;
  v_view = info;
}
