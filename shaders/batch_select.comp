#version 450 core
// Batched views (gl/batch.cpp), conservative or point-sampled: the GPU selects the triangles of
// rigid objects that a frame's views draw. A rigid shape lives in the resident buffer (uploaded once); per view and
// rigid object, a job names the shape's corners and how many triangles it has. One invocation
// per (job, triangle): the triangle's corners moved into ROI-local coordinates by the object's
// matrix for the view (as the batched vertex shaders move them), and kept when their box
// overlaps the ROI box grown by 1e-3 of its largest half extent (the host's culling keeps only
// triangles whose box overlaps the ROI box, in double: the growth covers the float rounding, so
// the selection holds every triangle the host's would; it does not cull further). A kept triangle is
// appended to the draw's entries, and its three vertices to the indirect draw's count (which the
// host set to the entries it wrote itself, those of deforming objects).
layout(local_size_x = 64) in;

#include "batch.inc"  // the views
layout(std430, binding = 4) writeonly buffer Entries { uvec4 entries[]; };
layout(std430, binding = 7) readonly buffer Resident { uvec4 resident[]; };
// first corner in the resident buffer, triangles, view << 1 | object, first invocation
layout(std430, binding = 9) readonly buffer Jobs { uvec4 jobs[]; };
layout(std430, binding = 10) buffer Command { uint vertex_count; uint instance_count; uint first; uint base_instance; };

uniform uint job_count;
uniform uint invocations;
uniform uint row;  // invocations per row of the dispatch (work groups along x times 64)

void main() {
  uint i = gl_GlobalInvocationID.y * row + gl_GlobalInvocationID.x;
  if (i >= invocations) return;
  uint lo = 0u, hi = job_count - 1u;  // the last job starting at or before i
  while (lo < hi) {
    uint mid = (lo + hi + 1u) >> 1;
    if (jobs[mid].w <= i) lo = mid; else hi = mid - 1u;
  }
  uvec4 job = jobs[lo];
  uint corner = job.x + 3u * (i - job.w);
  uint view = job.z >> 1;
  mat4 m = views[view].roi_from_object[job.z & 1u];
  vec3 h = views[view].half_box.xyz;
  vec3 reach = h + vec3(1.0e-3 * max(max(h.x, h.y), h.z));
  vec3 lo3 = vec3(3.0e38), hi3 = vec3(-3.0e38);
  for (uint k = 0u; k < 3u; ++k) {
    vec3 p = (m * vec4(uintBitsToFloat(resident[corner + k].xyz), 1.0)).xyz;
    lo3 = min(lo3, p);
    hi3 = max(hi3, p);
  }
  if (any(greaterThan(lo3, reach)) || any(lessThan(hi3, -reach))) return;
  uint slot = atomicAdd(vertex_count, 3u) / 3u;
  entries[slot] = uvec4(corner, job.z, resident[corner + 2u].w, 0u);
}
