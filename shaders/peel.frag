#version 450 core
// One peel pass. A layer texel holds (depth bits, object << 31 | ID + 1, dz/dx bits, dz/dy bits);
// a zero second channel marks "empty". Layer k+1 keeps, per texel, the nearest fragment of the
// objects drawn in this pass that lies behind layer k in (depth, rank) order, rank = object ^
// rank_flip: strictly deeper, or as deep and of a higher-ranked object, so that of two surfaces
// of different objects at the same depth both become layers (the depth test, GL_LESS, picks the
// nearest survivor; object A is drawn first). Alternate peeling draws one object per pass,
// starting with the object of rank 0; full peeling draws both.
layout(binding = 0) uniform usampler2D previous_layer;
uniform bool has_previous;
uniform uint object_bit;  // 0 for object A, 1 for object B
uniform uint rank_flip;   // full peeling: 0; alternate: the first object

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
    float prev_z = uintBitsToFloat(prev.x);
    bool behind = z > prev_z || (z == prev_z && (object_bit ^ rank_flip) > ((prev.y >> 31) ^ rank_flip));
    if (!behind) discard;
  }
  out_layer = uvec4(floatBitsToUint(z), (object_bit << 31) | (v_id + 1u), floatBitsToUint(gx),
                    floatBitsToUint(gy));
}
