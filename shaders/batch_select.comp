#version 450 core
// Batched views (gl/batch.cpp), conservative or point-sampled: the GPU selects the triangles of
// rigid objects and moving meshes that a frame's views draw. A rigid shape lives in the resident
// buffer (uploaded once), as do a moving mesh's corner records (its triangles: uploaded once; its
// vertices come with the frame's corners); per view and such object, a job names the corners
// and how many triangles it has. Two dispatches of this program (`pass`), one invocation per (job, triangle) each:
//   0. the triangle's corners moved into ROI-local coordinates by the object's matrix for the
//      view (as the batched vertex shaders move them), kept when their box overlaps the ROI box
//      grown by 1e-3 of its largest half extent (the host's culling keeps only triangles whose
//      box overlaps the ROI box, in double: the growth covers the float rounding, so the
//      selection holds every triangle the host's would), written to `staged`, and its box
//      merged into its object's region in the view;
//   1. the contact region: a staged triangle is kept when its box also overlaps the view's
//      region, the ROI box met with both objects' regions (the boxes of what each object has in
//      the view: the selection's, or, for triangles the host wrote, the host's), grown by the
//      same margin. A contact between a triangle of A and one of B lies in both their boxes,
//      so in that region: no triangle that can touch the other object is dropped (the host's
//      culling goes on with a grid; this is its first round). A kept triangle is appended to the
//      draw's entries, and its three vertices to the indirect draw's count (which the host set
//      to the entries it wrote itself, those of deforming objects).
// Regions are kept as ordered integers (a float's bits, flipped so that integer order is float
// order: atomicMin and atomicMax merge them). With a proximity margin (conservative views) every
// triangle's box is grown by half the margin in both passes (as the host's selection grows them).
layout(local_size_x = 64) in;

#define PEELCD_BATCH_CORNERS  // the resident buffer and the frame's corners, resident_corner()
#include "batch.inc"  // the views
layout(std430, binding = 4) writeonly buffer Entries { uvec4 entries[]; };
// Two records a job: (first corner in the resident buffer, triangles, view << 1 | object, first
// invocation), then (a moving mesh's first position in the frame's corners + 1, else 0; 0, 0, 0).
layout(std430, binding = 9) readonly buffer Jobs { uvec4 jobs[]; };
layout(std430, binding = 10) buffer Command { uint vertex_count; uint instance_count; uint first; uint base_instance; };
// Pass 0's triangles, as entries, and how many (the last word of the header).
layout(std430, binding = 13) buffer Staged { uvec4 staged_header; uvec4 staged[]; };
// Per view 12 words: object A's region (lo x, y, z, hi x, y, z), then B's, ordered integers.
layout(std430, binding = 14) buffer Regions { uint regions[]; };

uniform uint job_count;
uniform uint invocations;
uniform uint row;  // invocations per row of the dispatch (work groups along x times 64)
uniform int pass;
uniform int conservative;  // conservative views: triangle boxes grown by the proximity growth

// The growth of view's triangles (PeelJob::grow: 0 without a margin).
float grow_of(uint view) { return conservative != 0 ? views[view].box_lo.w : 0.0; }

uint ordered(float f) {
  uint b = floatBitsToUint(f);
  return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}
float from_ordered(uint e) { return uintBitsToFloat((e & 0x80000000u) != 0u ? e & 0x7fffffffu : ~e); }

// The ROI-local box of the triangle at `corner` of the resident buffer (`moving`: as
// resident_corner()), moved by `m`.
void triangle_box(uint corner, uint moving, mat4 m, out vec3 lo3, out vec3 hi3) {
  lo3 = vec3(3.0e38);
  hi3 = vec3(-3.0e38);
  for (uint k = 0u; k < 3u; ++k) {
    vec3 p = (m * vec4(resident_corner(corner + k, moving), 1.0)).xyz;
    lo3 = min(lo3, p);
    hi3 = max(hi3, p);
  }
}

void main() {
  uint i = gl_GlobalInvocationID.y * row + gl_GlobalInvocationID.x;
  if (pass == 1) {
    if (i >= staged_header.w) return;
    uvec4 e = staged[i];
    uint view = e.y >> 1;
    vec3 h = views[view].half_box.xyz;
    float margin = 1.0e-3 * max(max(h.x, h.y), h.z);
    uint r = 12u * view;
    vec3 lo_a = vec3(from_ordered(regions[r]), from_ordered(regions[r + 1u]), from_ordered(regions[r + 2u]));
    vec3 hi_a = vec3(from_ordered(regions[r + 3u]), from_ordered(regions[r + 4u]), from_ordered(regions[r + 5u]));
    vec3 lo_b = vec3(from_ordered(regions[r + 6u]), from_ordered(regions[r + 7u]), from_ordered(regions[r + 8u]));
    vec3 hi_b = vec3(from_ordered(regions[r + 9u]), from_ordered(regions[r + 10u]), from_ordered(regions[r + 11u]));
    vec3 lo_r = max(max(lo_a, lo_b), -h) - vec3(margin), hi_r = min(min(hi_a, hi_b), h) + vec3(margin);
    vec3 lo3, hi3;
    triangle_box(e.x, e.w, views[view].roi_from_object[e.y & 1u], lo3, hi3);
    lo3 -= vec3(grow_of(view));
    hi3 += vec3(grow_of(view));
    if (any(greaterThan(lo3, hi_r)) || any(lessThan(hi3, lo_r))) return;
    uint slot = atomicAdd(vertex_count, 3u) / 3u;
    entries[slot] = e;
    return;
  }
  if (i >= invocations) return;
  uint lo = 0u, hi = job_count - 1u;  // the last job starting at or before i
  while (lo < hi) {
    uint mid = (lo + hi + 1u) >> 1;
    if (jobs[2u * mid].w <= i) lo = mid; else hi = mid - 1u;
  }
  uvec4 job = jobs[2u * lo];
  uint moving = jobs[2u * lo + 1u].x;
  uint corner = job.x + 3u * (i - job.w);
  uint view = job.z >> 1;
  vec3 h = views[view].half_box.xyz;
  vec3 reach = h + vec3(1.0e-3 * max(max(h.x, h.y), h.z));
  vec3 lo3, hi3;
  triangle_box(corner, moving, views[view].roi_from_object[job.z & 1u], lo3, hi3);
  lo3 -= vec3(grow_of(view));
  hi3 += vec3(grow_of(view));
  if (any(greaterThan(lo3, reach)) || any(lessThan(hi3, -reach))) return;
  staged[atomicAdd(staged_header.w, 1u)] = uvec4(corner, job.z, resident[corner + 2u].w, moving);
  uint r = 12u * view + 6u * (job.z & 1u);
  for (uint k = 0u; k < 3u; ++k) {
    atomicMin(regions[r + k], ordered(lo3[k]));
    atomicMax(regions[r + 3u + k], ordered(hi3[k]));
  }
}
