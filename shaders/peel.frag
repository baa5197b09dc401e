#version 450 core
// One peel pass. A layer texel holds (depth bits, object << 31 | ID + 1, dz/dx bits, dz/dy bits);
// a zero second channel marks "empty". Layer k+1 keeps, per texel, the nearest fragment of the
// objects drawn in this pass whose depth is strictly greater than layer k's depth there (the
// depth test, GL_LESS, picks the nearest survivor). Alternate peeling draws one object per pass,
// full peeling draws both.
layout(binding = 0) uniform usampler2D previous_layer;
uniform bool has_previous;
uniform uint object_bit;  // 0 for object A, 1 for object B

flat in uint v_id;
layout(location = 0) out uvec4 out_layer;

void main() {
  float z = gl_FragCoord.z;
  // Depth slope of this triangle per texel, taken before any discard (derivatives need every
  // fragment of the quad). The PCS test uses it to widen epsilon where surfaces are steep.
  float gx = dFdx(z), gy = dFdy(z);
  if (has_previous) {
    uvec4 prev = texelFetch(previous_layer, ivec2(gl_FragCoord.xy), 0);
    if (prev.y == 0u) discard;                    // the texel ended at an empty layer
    if (!(z > uintBitsToFloat(prev.x))) discard;  // strictly behind the previous layer only
  }
  out_layer = uvec4(floatBitsToUint(z), (object_bit << 31) | (v_id + 1u), floatBitsToUint(gx),
                    floatBitsToUint(gy));
}
