#version 450 core
// One peel pass: triangles of one object in ROI-local coordinates (double on the CPU, float
// here), projected orthographically along the view direction and clipped to the ROI box.
layout(location = 0) in vec3 position;  // ROI-local, world units
layout(location = 1) in uint id;        // triangle ID of this corner (unique or paper, see core/id_map.h)

uniform mat4 clip_from_local;
uniform vec3 box_lo;  // ROI box, ROI-local
uniform vec3 box_hi;

flat out uint v_id;  // flat: the last (provoking) vertex decides the fragment's ID
out float gl_ClipDistance[6];

void main() {
  gl_Position = clip_from_local * vec4(position, 1.0);
  gl_ClipDistance[0] = position.x - box_lo.x;
  gl_ClipDistance[1] = box_hi.x - position.x;
  gl_ClipDistance[2] = position.y - box_lo.y;
  gl_ClipDistance[3] = box_hi.y - position.y;
  gl_ClipDistance[4] = position.z - box_lo.z;
  gl_ClipDistance[5] = box_hi.z - position.z;
  v_id = id;
}
