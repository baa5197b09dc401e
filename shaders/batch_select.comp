#version 450 core
// Batched views (gl/batch.cpp), conservative or point-sampled: the GPU selects the triangles of
// rigid objects and moving meshes that a frame's views draw. A rigid shape lives in the resident
// buffer (uploaded once), as do a moving mesh's corner records (its triangles: uploaded once; its
// vertices come with the frame's corners); per view and such object, a job names the corners
// and how many triangles it has. Three dispatches of this program (`pass`), one invocation per (job, triangle) of pass 0, per
// staged triangle of passes 1 and 2:
//   0. the triangle's corners moved into ROI-local coordinates by the object's matrix for the
//      view (as the batched vertex shaders move them), kept when their box overlaps the ROI box
//      grown by 1e-3 of its largest half extent (the host's culling keeps only triangles whose
//      box overlaps the ROI box, in double: the growth covers the float rounding, so the
//      selection holds every triangle the host's would), written to `staged`, and its box
//      merged into its object's region in the view;
//   1. the contact region: a staged triangle goes on when its box also overlaps the view's
//      region, the ROI box met with both objects' regions (the boxes of what each object has in
//      the view: the selection's, or, for triangles the host wrote, the host's), grown by the
//      same margin; it then marks, in its object's contact grid (16^3 cells over the region),
//      every cell its box grown by the margin reaches (a box over more than 64 cells marks them
//      all, one word);
//   2. the grid round: such a triangle is kept when a cell its grown box reaches is marked by
//      the other object (or the other object's triangles come from the host, which marks
//      nothing). A contact between a triangle of A and one of B lies in both their boxes, so in
//      the region, in one cell (the cell index is computed from a coordinate by the same
//      monotone float operations for both, so the contact's cell lies in both triangles' ranges,
//      the margin covering the boxes' float rounding): both mark it, both are kept. No
//      triangle that can touch the other object is dropped (the host's culling rounds, on the GPU).
//      A kept triangle is appended to the draw's entries, and its three vertices to the indirect
//      draw's count (which the host set to the entries it wrote itself, those of deforming objects).
// Regions are kept as ordered integers (a float's bits, flipped so that integer order is float
// order: atomicMin and atomicMax merge them). With a proximity margin (conservative views) every
// triangle's box is grown by half the margin in every pass (as the host's selection grows them).
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
// Per view 16 words: object A's region (lo x, y, z, hi x, y, z), then B's, ordered integers;
// then whether the selection picks A's triangles, B's (else the host wrote them), 0, 0.
layout(std430, binding = 14) buffer Regions { uint regions[]; };
// Per view and object (view << 1 | object) kGridWords words: 16^3 cells' bits, then "all".
const uint kGridCells = 16u, kGridWords = 16u * 16u * 16u / 32u + 1u;
layout(std430, binding = 17) buffer Grid { uint grid[]; };

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

// The view's contact region (the ROI box met with both objects' regions), grown by `margin`.
void view_region(uint view, float margin, out vec3 lo_r, out vec3 hi_r) {
  vec3 h = views[view].half_box.xyz;
  uint r = 16u * view;
  vec3 lo_a = vec3(from_ordered(regions[r]), from_ordered(regions[r + 1u]), from_ordered(regions[r + 2u]));
  vec3 hi_a = vec3(from_ordered(regions[r + 3u]), from_ordered(regions[r + 4u]), from_ordered(regions[r + 5u]));
  vec3 lo_b = vec3(from_ordered(regions[r + 6u]), from_ordered(regions[r + 7u]), from_ordered(regions[r + 8u]));
  vec3 hi_b = vec3(from_ordered(regions[r + 9u]), from_ordered(regions[r + 10u]), from_ordered(regions[r + 11u]));
  lo_r = max(max(lo_a, lo_b), -h) - vec3(margin);
  hi_r = min(min(hi_a, hi_b), h) + vec3(margin);
}

// The grid cells (clamped to the grid) that [lo3, hi3] reaches, over the region [lo_r, hi_r]:
// floor((x - lo_r) * cells / extent), monotone in x.
void cell_range(vec3 lo3, vec3 hi3, vec3 lo_r, vec3 hi_r, out uvec3 c0, out uvec3 c1) {
  vec3 scale = float(kGridCells) / max(hi_r - lo_r, vec3(1e-30));
  vec3 f0 = clamp(floor((lo3 - lo_r) * scale), vec3(0.0), vec3(float(kGridCells - 1u)));
  vec3 f1 = clamp(floor((hi3 - lo_r) * scale), vec3(0.0), vec3(float(kGridCells - 1u)));
  c0 = uvec3(f0);
  c1 = uvec3(f1);
}

void main() {
  uint i = gl_GlobalInvocationID.y * row + gl_GlobalInvocationID.x;
  if (pass >= 1) {
    if (i >= staged_header.w) return;
    uvec4 e = staged[i];
    uint view = e.y >> 1;
    vec3 h = views[view].half_box.xyz;
    float margin = 1.0e-3 * max(max(h.x, h.y), h.z);
    vec3 lo_r, hi_r;
    view_region(view, margin, lo_r, hi_r);
    vec3 lo3, hi3;
    triangle_box(e.x, e.w, views[view].roi_from_object[e.y & 1u], lo3, hi3);
    lo3 -= vec3(grow_of(view));
    hi3 += vec3(grow_of(view));
    if (any(greaterThan(lo3, hi_r)) || any(lessThan(hi3, lo_r))) return;
    uvec3 c0, c1;
    cell_range(lo3 - vec3(margin), hi3 + vec3(margin), lo_r, hi_r, c0, c1);
    uvec3 n = c1 - c0 + uvec3(1u);
    if (pass == 1) {  // mark this object's cells
      uint base = kGridWords * e.y;
      if (n.x * n.y * n.z > 64u) {
        atomicOr(grid[base + kGridWords - 1u], 1u);
        return;
      }
      for (uint z = c0.z; z <= c1.z; ++z)
        for (uint y = c0.y; y <= c1.y; ++y)
          for (uint x = c0.x; x <= c1.x; ++x) {
            uint cell = (z * kGridCells + y) * kGridCells + x;
            atomicOr(grid[base + (cell >> 5)], 1u << (cell & 31u));
          }
      return;
    }
    // pass 2: kept when the other object marked a cell of this triangle's range
    uint other = e.y ^ 1u;
    bool keep = regions[16u * view + 12u + (other & 1u)] == 0u;  // the host's triangles: no marks
    uint base = kGridWords * other;
    keep = keep || grid[base + kGridWords - 1u] != 0u;
    for (uint z = c0.z; z <= c1.z && !keep; ++z)
      for (uint y = c0.y; y <= c1.y && !keep; ++y)
        for (uint x = c0.x; x <= c1.x && !keep; ++x) {
          uint cell = (z * kGridCells + y) * kGridCells + x;
          keep = (grid[base + (cell >> 5)] & (1u << (cell & 31u))) != 0u;
        }
    if (!keep) return;
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
  uint r = 16u * view + 6u * (job.z & 1u);
  for (uint k = 0u; k < 3u; ++k) {
    atomicMin(regions[r + k], ordered(lo3[k]));
    atomicMax(regions[r + 3u + k], ordered(hi3[k]));
  }
}
