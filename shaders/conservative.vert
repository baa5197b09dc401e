#version 450 core
// Conservative mode (docs/accuracy.md), step 0: each corner in ROI-local coordinates, and the
// size of what the float products that made it summed (its error bound's scale).
layout(location = 0) in vec3 in_position;  // ROI-local, or a rigid shape's local
layout(location = 1) in uint id;           // unused here: the resolve reads IDs by draw order

uniform mat4 roi_from_object;  // identity, or a rigid object's pose (ROI-local from its shape)

out vec3 v_local;
out vec3 v_mag;  // |R| |s| + |t| componentwise
flat out uint v_order;  // the triangle's place in the draw order (as shaders/peel.vert)

void main() {
  v_local = (roi_from_object * vec4(in_position, 1.0)).xyz;
  vec3 a = abs(in_position);
  v_mag = abs(roi_from_object[0].xyz) * a.x + abs(roi_from_object[1].xyz) * a.y +
          abs(roi_from_object[2].xyz) * a.z + abs(roi_from_object[3].xyz);
  v_order = uint(gl_VertexID) / 3u;
}
