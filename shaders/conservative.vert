#version 450 core
// Conservative mode (docs/accuracy.md), step 0: each corner in ROI-local coordinates, and the
// size of what the float products that made it summed (its error bound's scale).
// PEELCD_BATCH (defined by the GL stage for its batched program): every ROI view of a frame in
// one draw (GlImageStage::peel_batch); each triangle's view and object (A or B) come from a
// buffer, and its corners are moved by its view's matrix.
layout(location = 0) in vec3 in_position;  // ROI-local, or a rigid shape's local
layout(location = 1) in uint id;           // unused here: the resolve reads IDs by draw order

#ifdef PEELCD_BATCH
struct BatchView {
  mat4 clip_from_local;
  mat4 roi_from_object[2];  // per object: identity, or a rigid object's pose (ROI-local)
  ivec4 info;               // resolution, first texel in the packed k-buffer, -, -
};
layout(std430, binding = 3) readonly buffer Views { BatchView views[]; };
layout(std430, binding = 4) readonly buffer Triangles { uint triangle_view[]; };  // view << 1 | object
flat out uint v_view;  // view << 1 | object
#else
uniform mat4 roi_from_object;  // identity, or a rigid object's pose (ROI-local from its shape)
#endif

out vec3 v_local;
out vec3 v_mag;  // |R| |s| + |t| componentwise
flat out uint v_order;  // the triangle's place in the draw order (as shaders/peel.vert; all views)

void main() {
#ifdef PEELCD_BATCH
  uint info = triangle_view[uint(gl_VertexID) / 3u];
  mat4 roi_from_object = views[info >> 1].roi_from_object[info & 1u];
  v_view = info;
#endif
  v_local = (roi_from_object * vec4(in_position, 1.0)).xyz;
  vec3 a = abs(in_position);
  v_mag = abs(roi_from_object[0].xyz) * a.x + abs(roi_from_object[1].xyz) * a.y +
          abs(roi_from_object[2].xyz) * a.z + abs(roi_from_object[3].xyz);
  v_order = uint(gl_VertexID) / 3u;
}
