#version 450 core
// Layer k+1 of alternate surface peeling: the nearest fragment of this object whose depth is
// strictly greater than layer k's depth at the texel. The hardware depth test (GL_LESS) keeps
// the nearest survivor. A layer texel stores (depth bits, ID + 1); ID + 1 == 0 marks "empty".
layout(binding = 0) uniform usampler2D previous_layer;
uniform bool has_previous;

flat in uint v_id;
layout(location = 0) out uvec2 out_layer;

void main() {
  float z = gl_FragCoord.z;
  if (has_previous) {
    uvec2 prev = texelFetch(previous_layer, ivec2(gl_FragCoord.xy), 0).xy;
    if (prev.y == 0u) discard;                 // the texel ended at an empty layer
    if (!(z > uintBitsToFloat(prev.x))) discard;  // strictly behind the previous layer only
  }
  out_layer = uvec2(floatBitsToUint(z), v_id + 1u);
}
