#version 450 core
// Conservative mode (docs/accuracy.md), step 0: each corner in ROI-local coordinates, and the
// size of what the float products that made it summed (its error bound's scale).
// PEELCD_BATCH (defined by the GL stage for its batched program): every ROI view of a frame in
// one indirect draw (GlImageStage::peel_batch). Nothing comes through vertex attributes: triangle
// k of the draw is entries[k] (shaders/batch.inc), its corners moved by the view's matrix for its
// object.
#include "conservative.inc"  // cover_corner()
#ifdef PEELCD_BATCH
#define PEELCD_BATCH_DRAW
#include "batch.inc"  // the views, the entries, batch_corner()
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
  vec3 in_position = batch_corner(v_view);
  mat4 roi_from_object = views[v_view >> 1].roi_from_object[v_view & 1u];
#endif
  cover_corner(in_position, roi_from_object, v_local, v_mag);
  v_order = uint(gl_VertexID) / 3u;
}
