#version 450 core
// One peel pass: triangles of one object in ROI-local coordinates (double on the CPU, float
// here), projected orthographically along the view direction and clipped to the ROI box.
layout(location = 0) in vec3 in_position;  // ROI-local, world units (or a rigid shape's local)
layout(location = 1) in uint id;        // triangle ID of this corner (unique or paper, see core/id_map.h)

uniform mat4 clip_from_local;
uniform mat4 roi_from_object;  // identity, or a rigid object's pose (ROI-local from its shape)
uniform vec3 box_lo;  // ROI box, ROI-local
uniform vec3 box_hi;

flat out uint v_id;  // flat: the last (provoking) vertex decides the fragment's ID
// The triangle's place in the draw order (single-pass peeling breaks depth ties with it):
// corners are drawn three per triangle in order, as arrays or by indices 3t + k in ascending t.
flat out uint v_order;
out float gl_ClipDistance[6];

void main() {
  vec3 p = (roi_from_object * vec4(in_position, 1.0)).xyz;
  gl_Position = clip_from_local * vec4(p, 1.0);
  gl_ClipDistance[0] = p.x - box_lo.x;
  gl_ClipDistance[1] = box_hi.x - p.x;
  gl_ClipDistance[2] = p.y - box_lo.y;
  gl_ClipDistance[3] = box_hi.y - p.y;
  gl_ClipDistance[4] = p.z - box_lo.z;
  gl_ClipDistance[5] = box_hi.z - p.z;
  v_id = id;
  v_order = uint(gl_VertexID) / 3u;
}
