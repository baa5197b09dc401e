#version 450 core
// Conservative mode (docs/accuracy.md), step 0: each corner in ROI-local coordinates, and the
// size of what the float products that made it summed (its error bound's scale).
// PEELCD_BATCH (defined by the GL stage for its batched program): every ROI view of a frame in
// one indirect draw (GlImageStage::peel_batch). Nothing comes through vertex attributes: triangle
// k of the draw is entries[k], which names its first corner (in a rigid shape's resident buffer,
// or, bit 31 set, in the frame's corners of deforming objects), its view and object (A or B); its
// corners are moved by the view's matrix for that object. The entries of rigid objects are
// written by the selection pass (shaders/conservative_select.comp), the others by the host.
#ifdef PEELCD_BATCH
struct BatchView {
  mat4 clip_from_local;
  mat4 roi_from_object[2];  // per object: identity, or a rigid object's pose (ROI-local)
  ivec4 info;               // resolution, first texel in the packed k-buffer, -, -
  vec4 half_box;  // the ROI box's half extents (ROI-local: the box is centred), -
};
layout(std430, binding = 3) readonly buffer Views { BatchView views[]; };
// first corner (bit 31: frame corners), view << 1 | object, the provoking corner's ID, 0
layout(std430, binding = 4) readonly buffer Entries { uvec4 entries[]; };
layout(std430, binding = 7) readonly buffer Resident { uvec4 resident[]; };      // x, y, z float bits; ID
layout(std430, binding = 8) readonly buffer FrameCorners { uvec4 frame_corners[]; };
flat out uint v_view;  // view << 1 | object
#else
layout(location = 0) in vec3 in_position;  // ROI-local, or a rigid shape's local
layout(location = 1) in uint id;           // unused here: the resolve reads IDs by draw order
uniform mat4 roi_from_object;  // identity, or a rigid object's pose (ROI-local from its shape)
#endif

out vec3 v_local;
out vec3 v_mag;  // |R| |s| + |t| componentwise
flat out uint v_order;  // the triangle's place in the draw order (as shaders/peel.vert; all views)

void main() {
#ifdef PEELCD_BATCH
  uvec4 e = entries[uint(gl_VertexID) / 3u];
  uint corner = (e.x & 0x7fffffffu) + uint(gl_VertexID) % 3u;
  vec3 in_position = uintBitsToFloat((e.x >> 31) != 0u ? frame_corners[corner].xyz : resident[corner].xyz);
  mat4 roi_from_object = views[e.y >> 1].roi_from_object[e.y & 1u];
  v_view = e.y;
#endif
  v_local = (roi_from_object * vec4(in_position, 1.0)).xyz;
  vec3 a = abs(in_position);
  v_mag = abs(roi_from_object[0].xyz) * a.x + abs(roi_from_object[1].xyz) * a.y +
          abs(roi_from_object[2].xyz) * a.z + abs(roi_from_object[3].xyz);
  v_order = uint(gl_VertexID) / 3u;
}
