// Batched views (GlImageStage::peel_batch): the ROI views of a frame packed into one compact
// k-buffer and drawn through shaders/conservative.* (conservative views) or shaders/peel.vert and
// abuffer.frag (point-sampled views, the single-pass peeler's), with PEELCD_BATCH. Rigid shapes are
// resident (one buffer, each shape copied there once); per view and rigid object a job goes to
// the selection passes (shaders/batch_select.comp), which append the triangles reaching the
// ROI box and the view's contact region to the draw's entries; deforming objects' triangles
// come from the host (their corners uploaded per frame). A count pass and a fill pass (indirect draws over the entries) fill the
// k-buffer; each view's part is then resolved on the host (core/image/kbuffer.cpp) or by one dispatch
// (shaders/conservative_batch_resolve.comp, shaders/abuffer_resolve.comp). Per view, a buffer
// holds its matrix, the objects' poses, its resolution, its first texel, its ROI box and, point
// sampled, its PCS threshold, slope and peel mode (shaders/batch.inc). The arithmetic per texel is
// that of the one-view draw, so with the host's selection (GlOptions::gpu_select false, and views
// capturing layers) a view gives the same layers and PCS either way (a point-sampled view smaller
// than the batch's largest is placed by one more scaling: its samples may differ in the last bit).
#include "stage_impl.h"
#include "peelcd/core/image/conservative.h"
#include "peelcd/core/image/texel.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace peelcd::gl {

void GlImageStage::peel_batch(const PeelJob* jobs, std::size_t count, PeelResult* outs, Timings& timings) {
  Impl& s = *impl_;
  std::size_t i = 0;
  while (i < count) {
    // A run of conservative views (on the GPU resolve, without layer capture: dumps and goldens
    // take every layer of a view, the one-view path), or of point-sampled views of the
    // single-pass peeler that capture nothing (the multi-pass peeler draws per layer and view).
    const bool conservative = jobs[i].conservative;
    const auto batched = [&](const PeelJob& job) {
      if (job.conservative != conservative) return false;
      return conservative ? s.host_resolve() || !job.capture : s.options.peeler == Peeler::abuffer && !job.capture;
    };
    std::size_t end = i;
    while (end < count && batched(jobs[end])) ++end;
    // One view alone is drawn on its own unless Impl::batched_alone() (the one-view resolve would
    // hand a deep texel to the host).
    if ((end - i == 1 && !s.batched_alone(jobs[i])) || end == i || !s.options.batch) {
      s.peel_one(jobs[i], outs[i], timings);
      ++i;
      continue;
    }
    while (i < end) i += s.peel_batched_views(jobs + i, end - i, outs + i, timings);
  }
  s.hand_clocks(timings);
}

namespace {

// One view's record in the views buffer (shaders/batch.inc, std430: mat4 clip, mat4 poses[2],
// ivec4 info, vec4 half_box, vec4 box_lo, vec4 box_hi).
constexpr std::size_t kViewWords = 16 + 32 + 4 + 4 + 4 + 4;
// The selection's contact grid (shaders/batch_select.comp): per view and object, 16^3 cells'
// bits and one word that marks them all.
constexpr std::size_t kGridWords = 16 * 16 * 16 / 32 + 1;

void put_matrix(std::vector<float>& out, const float* m) { out.insert(out.end(), m, m + 16); }

// A float as an integer of the same order (shaders/batch_select.comp's regions).
std::uint32_t ordered(float f) {
  const std::uint32_t b = texel::bits_of(f);
  return (b & 0x80000000u) ? ~b : b | 0x80000000u;
}

// An object's region in a view (shaders/batch_select.comp): lo x, y, z, hi x, y, z.
void put_region(std::vector<std::uint32_t>& out, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  for (int k = 0; k < 3; ++k) out.push_back(ordered(lo[k]));
  for (int k = 0; k < 3; ++k) out.push_back(ordered(hi[k]));
}

}  // namespace

// Views jobs[0..count) packed: as many as one k-buffer holds, their geometry gathered and
// uploaded, the rigid objects' triangles selected on the GPU, the count pass, the offsets, the
// fill pass, the resolve (GPU, or host). A first view that fills the counts alone, or a batch
// with more fragments than one buffer holds, goes view by view (peel_one()).
std::size_t GlImageStage::Impl::peel_batched_views(const PeelJob* jobs, std::size_t count, PeelResult* outs,
                                                   Timings& t) {
  BatchRun run;
  run.point = !jobs[0].conservative;  // every job of the run is alike
  // Fewer than two views go on their own, but for a lone view batched_alone() takes.
  const std::size_t planned = plan_batch(jobs, count, run);
  if (planned == 0 || (planned < 2 && !(count == 1 && batched_alone(jobs[0])))) {
    peel_one(jobs[0], outs[0], t);
    return 1;
  }
  const auto t0 = Clock::now();
  gather_batch(jobs, outs, run);
  upload_batch(run);
  t.upload += ms_since(t0);

  const auto t_gpu = Clock::now();
  count_batch(run, t);
  outs[0].triangles_indexed += run.selected;
  if (run.total > run.most) {  // more fragments than one buffer holds: each view on its own
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    gl.BindVertexArray(vao);
    for (std::size_t j = 0; j < run.take; ++j) peel_one(jobs[j], outs[j], t);
    return run.take;
  }
  fill_batch(run);
  if (!host_resolve()) {
    if (resolve_batch_on_gpu(run.take, run.texels, run.point, outs, t)) {
      t.gpu += ms_since(t_gpu);
      outs[0].gl_passes = 2;  // the count and fill draws for the batch
      return run.take;
    }
    // A texel deeper than the GPU resolve takes (point sampling: PEELCD_GPU_RESOLVE_DEPTH
    // fragments): the batch resolved on the host instead, said in views_host_resolved.
    counters->views_host_resolved += run.take;
    for (std::size_t j = 0; j < run.take; ++j) outs[j].pcs.clear();
    if (run.gpu_sum) {
      read_batch_counts(run.texels, t);
      run.deepest = batch.deepest;
    }
  }
  const double map_ms = resolve_batch_on_host(jobs, outs, run, t);
  t.gpu += ms_since(t_gpu) - map_ms;
  outs[0].gl_passes = 2;  // the count and fill draws for the batch
  return run.take;
}

// How many of the views one packed k-buffer holds at the current slots (the largest storage
// block): their texels and largest side into `run`.
std::size_t GlImageStage::Impl::plan_batch(const PeelJob* jobs, std::size_t count, BatchRun& run) const {
  run.most = std::min(max_storage_block / 16, fetchable());
  run.texels = 0;
  run.largest = 0;
  for (run.take = 0; run.take < count; ++run.take) {
    const int n = jobs[run.take].view.resolution;
    const std::size_t tx = std::size_t(n) * std::size_t(n);
    if (run.texels + tx > run.most) break;
    run.texels += tx;
    run.largest = std::max(run.largest, n);
  }
  return run.take;
}

// The batch's host data: per view its record (matrices, info, box, PCS test), per object its
// triangles (entries, corners of deforming objects) or its selection job (rigid objects, GPU
// selection) and its region.
void GlImageStage::Impl::gather_batch(const PeelJob* jobs, PeelResult* outs, BatchRun& run) {
  batch.corners.clear();
  batch.entry_data.clear();
  batch.job_data.clear();
  batch.ids.clear();
  batch.view_data.clear();
  batch.view_data.reserve(run.take * kViewWords);
  batch.region_data.clear();
  run.invocations = 0;
  shape_uploads = 0;  // the batch's, reported on its first view
  batch.moving_bases.clear();
  batch.moving_order.clear();
  batch.position_count = 0;
  // Every rigid shape and moving mesh of the batch resident first: adding one may move the others
  // (compaction), so their first corners are read only after all are in.
  for (std::size_t j = 0; j < run.take; ++j)
    for (int slot = 0; slot < 2; ++slot) {
      const Object& object = *jobs[j].objects[slot];
      if (object.rigid && object.rigid->shape) resident_base(object.rigid->shape, jobs[j].ids);
      if (moving_mesh(object)) resident_topology(*object.moving, jobs[j].ids);
    }
  std::size_t base = 0;
  for (std::size_t j = 0; j < run.take; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& out = outs[j];
    out.clear();
    const std::array<float, 16> clip = job.view.clip_from_local();
    put_matrix(batch.view_data, clip.data());
    std::uint32_t selected_on_gpu[2];
    for (int slot = 0; slot < 2; ++slot) selected_on_gpu[slot] = gather_batch_object(job, j, slot, out, run);
    batch.region_data.insert(batch.region_data.end(), {selected_on_gpu[0], selected_on_gpu[1], 0u, 0u});
    put_view_record(job, base, run.point, out);
    base += std::size_t(job.view.resolution) * std::size_t(job.view.resolution);
  }
  outs[0].shape_uploads = shape_uploads;
  run.host_entries = batch.entry_data.size();
  if (std::max({run.host_entries + run.invocations, batch.corners.size(), batch.position_count}) >= 0x7fffffffu / 3)
    throw GlError("peelcd::gl::GlImageStage: a batch of " + std::to_string(run.host_entries + run.invocations) +
                  " triangles and " + std::to_string(batch.position_count) +
                  " moving vertices is more than a draw's order holds (2^31 / 3)");
}

// One object of view j: its pose (ROI-local from shape-local for a rigid object, a shift for a
// moving mesh), then its triangles; returns whether the selection pass picks them (else the host
// listed them). The object's region in the view (the selection's contact-region round): empty,
// for the selection to merge its triangles' boxes into; everything, for the host's selection of
// a rigid object or moving mesh (its ROI-local corners are the GPU's to compute); the box of the
// corners uploaded, for a deforming object.
bool GlImageStage::Impl::gather_batch_object(const PeelJob& job, std::size_t j, int slot, PeelResult& out,
                                             BatchRun& run) {
  const RoiView& view = job.view;
  const Object& object = *job.objects[slot];
  const bool rigid = object.rigid && object.rigid->shape;
  const bool moving = !rigid && moving_mesh(object);
  const Mesh& mesh = rigid ? *object.rigid->shape : drawn_mesh(object);
  const std::uint32_t view_object = std::uint32_t(j) << 1 | std::uint32_t(slot);
  float model[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (rigid || moving) {  // composed in double, rounded once (as prepare()); a moving mesh's: a shift
    Eigen::Affine3d m = rigid ? object.rigid->pose : Eigen::Affine3d::Identity();
    m.translation() -= view.center;
    const Eigen::Matrix4d mm = m.matrix();
    for (int i = 0; i < 16; ++i) model[i] = float(mm(i % 4, i / 4));
  }
  put_matrix(batch.view_data, model);
  constexpr float inf = std::numeric_limits<float>::infinity();
  if (rigid || moving) {
    const std::size_t first = rigid ? resident_base(object.rigid->shape, job.ids) : resident_topology(*object.moving, job.ids);
    // A moving mesh's vertices: in the positions once a batch (its first + 1 in the entries).
    const std::uint32_t positions = moving ? moving_positions(mesh) + 1u : 0u;
    if (options.gpu_select && !job.capture) {  // the selection pass picks its triangles (no list read)
      if (!mesh.triangles.empty()) {
        batch.job_data.push_back({std::uint32_t(first), std::uint32_t(mesh.triangles.size()), view_object,
                                  std::uint32_t(run.invocations)});
        batch.job_data.push_back({positions, 0u, 0u, 0u});
      }
      run.invocations += mesh.triangles.size();
      put_region(batch.region_data, Eigen::Vector3f::Constant(inf), Eigen::Vector3f::Constant(-inf));
      return true;
    }
    put_region(batch.region_data, Eigen::Vector3f::Constant(-inf), Eigen::Vector3f::Constant(inf));
    const std::vector<std::uint32_t>& tris = job_triangles(job, slot, selected[slot]);
    for (const std::uint32_t tri : tris) {  // the host's selection, from the resident corners
      batch.entry_data.push_back(
          {std::uint32_t(first + 3 * std::size_t(tri)), view_object, corner_id(mesh, tri, 2, job.ids), positions});
      batch.ids.push_back(batch.entry_data.back()[2]);
    }
    out.triangles_indexed += tris.size();
    return false;
  }
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(inf), hi = Eigen::Vector3f::Constant(-inf);
  const std::vector<std::uint32_t>& tris = job_triangles(job, slot, selected[slot]);
  for (const std::uint32_t tri : tris) {
    const std::uint32_t corner = std::uint32_t(batch.corners.size());
    for (int k = 0; k < 3; ++k) {
      const Vec3 local = mesh.vertices[mesh.triangles[tri][k]] - view.center;
      batch.corners.push_back({float(local.x()), float(local.y()), float(local.z()), corner_id(mesh, tri, k, job.ids)});
      const Eigen::Vector3f p(batch.corners.back().x, batch.corners.back().y, batch.corners.back().z);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    batch.entry_data.push_back({0x80000000u | corner, view_object, batch.corners.back().id, 0u});
    batch.ids.push_back(batch.corners.back().id);
  }
  const float grow = float(job.grow);  // proximity: the region of the triangles grown (batch_select.comp)
  put_region(batch.region_data, (lo.array() - grow).matrix(), (hi.array() + grow).matrix());
  out.triangles_uploaded += tris.size();
  return false;
}

// The rest of a view's record: info (resolution, first texel, peel flags), half box, the clip
// planes and the PCS test as the one-view point-sampled draw has them.
void GlImageStage::Impl::put_view_record(const PeelJob& job, std::size_t base, bool point, PeelResult& out) {
  const RoiView& view = job.view;
  const std::int32_t flags = point ? std::int32_t(job.peel == PeelMode::full) << 1 | std::int32_t(job.first & 1) : 0;
  float grow_x = 0.0f, grow_z = 0.0f;  // conservative: the proximity growth (0 in point sampling)
  if (!point) conservative::grow_of(job.grow, view.texel(), 2.0 * view.half_depth, grow_x, grow_z);
  const std::int32_t info[4] = {view.resolution, std::int32_t(base), flags, 0};
  float info_words[4];
  std::memcpy(info_words, info, sizeof info);
  info_words[3] = grow_z;
  batch.view_data.insert(batch.view_data.end(), info_words, info_words + 4);
  const Vec3 half = 0.5 * view.box.extent();
  batch.view_data.insert(batch.view_data.end(), {float(half.x()), float(half.y()), float(half.z()), grow_x});
  out.epsilon_window = point ? float(view.world_to_window_depth(job.epsilon)) : 0.0f;
  out.slope = point ? float(job.slope) : 0.0f;
  const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
  const float w = point ? out.epsilon_window : float(job.grow);  // conservative: the growth, world units
  batch.view_data.insert(batch.view_data.end(), {float(lo.x()), float(lo.y()), float(lo.z()), w});
  batch.view_data.insert(batch.view_data.end(), {float(hi.x()), float(hi.y()), float(hi.z()), out.slope});
}

// `bytes` of `data` into `buffer`, grown (to at least `reserve` bytes) when it is too small.
void GlImageStage::Impl::upload_batch_buffer(GLuint buffer, std::size_t& capacity, const void* data,
                                             std::size_t bytes, std::size_t reserve, bool geometry) {
  if (std::max(bytes, reserve) > capacity || capacity == 0) {
    capacity = std::max({bytes, reserve, capacity * 3 / 2, std::size_t(16)});
    gl.NamedBufferData(buffer, GLsizeiptr(capacity), nullptr, GL_STREAM_DRAW);
  }
  if (bytes == 0) return;
  geometry ? upload_geometry(buffer, 0, GLsizeiptr(bytes), data) : upload_buffer(buffer, 0, GLsizeiptr(bytes), data);
}

// The batch's corners, view records, entries (the host's first, room after them for every
// triangle the selection may keep), selection jobs and the indirect draw's command.
void GlImageStage::Impl::upload_batch(const BatchRun& run) {
  upload_batch_buffer(batch.frame, batch.frame_capacity, batch.corners.data(), batch.corners.size() * sizeof(GpuVertex),
                      0, true);
  upload_positions();
  upload_batch_buffer(batch.views, batch.views_capacity, batch.view_data.data(), batch.view_data.size() * sizeof(float),
                      0, false);
  upload_batch_buffer(batch.entries, batch.entries_capacity, batch.entry_data.data(), run.host_entries * kBatchEntryBytes,
                      (run.host_entries + run.invocations) * kBatchEntryBytes, true);
  upload_batch_buffer(batch.jobs, batch.jobs_capacity, batch.job_data.data(), batch.job_data.size() * kBatchEntryBytes, 0, false);
  const std::uint32_t command[4] = {std::uint32_t(3 * run.host_entries), 1u, 0u, 0u};
  upload_buffer(batch.command, 0, sizeof command, command);
}

// The selection pass: rigid objects' and moving meshes' triangles in each view's ROI box staged,
// their objects' regions merged; then its contact-region round (those that reach the view's
// region mark their cells of the view's grid) and its grid round (those in a cell the other
// object marked appended to the entries) (shaders/batch_select.comp).
void GlImageStage::Impl::select_batch(const BatchRun& run) {
  upload_batch_buffer(batch.regions, batch.regions_capacity, batch.region_data.data(),
                      batch.region_data.size() * sizeof(std::uint32_t), 0, false);
  upload_batch_buffer(batch.staged, batch.staged_capacity, nullptr, 0, (run.invocations + 1) * kBatchEntryBytes, false);
  const std::uint32_t staged_header[4] = {0, 0, 0, 0};
  upload_buffer(batch.staged, 0, sizeof staged_header, staged_header);
  const std::size_t grid_bytes = run.take * 2 * kGridWords * sizeof(std::uint32_t);  // cleared: no cell marked
  upload_batch_buffer(batch.grid, batch.grid_capacity, nullptr, 0, grid_bytes, false);
  clear_buffer(batch.grid, GLsizeiptr(grid_bytes));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 17, batch.grid);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, batch.jobs);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, batch.command);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 13, batch.staged);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 14, batch.regions);
  gl.UseProgram(select.id);
  const std::size_t groups = (run.invocations + 63) / 64;
  const std::size_t gx = std::min<std::size_t>(groups, 65535), gy = (groups + gx - 1) / gx;
  gl.Uniform1ui(select.jobs, GLuint(batch.job_data.size() / 2));  // two records a job
  gl.Uniform1ui(select.invocations, GLuint(run.invocations));
  gl.Uniform1ui(select.row, GLuint(gx * 64));
  gl.Uniform1i(select.conservative, run.point ? 0 : 1);
  for (int pass = 0; pass < 3; ++pass) {
    gl.Uniform1i(select.pass, pass);
    dispatch(GLuint(gx), GLuint(gy), 1, GpuPass::select);
    barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  }
}

// The selection (rigid objects on the GPU), then the count pass: each texel's fragments counted,
// nothing stored; then the counts into offsets and the total (run.total), and the triangles the
// selection added (run.selected).
void GlImageStage::Impl::count_batch(BatchRun& run, Timings& t) {
  ensure_bare_fbo(std::max(run.largest, bare_size));
  ensure_kbuffer(run.texels, 1);  // the counts; the fragments are sized by the count pass
  clear_buffer(count_buffer, GLsizeiptr(run.texels * 4));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, count_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, batch.views);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, batch.entries);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, resident_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, batch.frame);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 16, batch.positions);
  if (run.invocations) select_batch(run);
  gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, batch.command);
  gl.UseProgram(run.point ? point_batch.id : cons_batch.id);
  gl.Uniform1i(run.point ? point_batch.viewport : cons_batch.viewport, run.largest);  // kept by the program
  gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
  gl.Viewport(0, 0, run.largest, run.largest);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_CULL_FACE);
  gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
  // Point sampling clips to the ROI box; the conservative intervals clip in depth themselves.
  for (int i = 0; i < 6; ++i) run.point ? gl.Enable(GL_CLIP_DISTANCE0 + i) : gl.Disable(GL_CLIP_DISTANCE0 + i);
  gl.BindVertexArray(batch.vao);
  cover_batch_pass(run, true);
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  batch_offsets(run, t);
}

// A pass over the batch's triangles (the count pass, or the fill pass): the indirect draw, or,
// for conservative views with GlOptions::coverage compute, one invocation per entry the draw
// could have (the host's and every triangle the selection may append; those past the command's
// count return at once) running the draw's arithmetic (shaders/conservative_cover.comp).
void GlImageStage::Impl::cover_batch_pass(const BatchRun& run, bool count_only) {
  if (run.point || !compute_coverage(run.largest)) {
    gl.UseProgram(run.point ? point_batch.id : cons_batch.id);
    gl.Uniform1i(run.point ? point_batch.count_only : cons_batch.count_only, count_only ? 1 : 0);
    timed_draw([&] { gl.DrawArraysIndirect(GL_TRIANGLES, nullptr); });
    return;
  }
  const std::size_t groups = (run.host_entries + run.invocations + 63) / 64;
  if (groups == 0) return;
  const std::size_t gx = std::min<std::size_t>(groups, 65535), gy = (groups + gx - 1) / gx;
  ensure_cover_programs();
  const CoverProgram& program = cover_batch[count_only ? 1 : 0];
  gl.UseProgram(program.id);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, batch.command);
  gl.Uniform1ui(program.row, GLuint(gx * 64));
  dispatch(GLuint(gx), GLuint(gy), 1, GpuPass::cover);
}

// The counts into offsets, the k-buffer sized to hold them all; the triangles drawn (the
// command's count). The host resolve reads the counts anyway: a prefix sum on the host, the
// offsets uploaded (by fill_batch()). The GPU resolve: the prefix sum on the GPU
// (shaders/prefix_sum.comp), only the total read back.
void GlImageStage::Impl::batch_offsets(BatchRun& run, Timings& t) {
  const std::size_t offset_bytes = run.texels * 4;
  if (offset_bytes > batch.offsets_capacity) {
    batch.offsets_capacity = std::max(offset_bytes, batch.offsets_capacity * 3 / 2);
    gl.NamedBufferData(batch.offset_buffer, GLsizeiptr(batch.offsets_capacity), nullptr, GL_DYNAMIC_COPY);
  }
  const std::size_t blocks = (run.texels + 1023) / 1024;
  run.gpu_sum = !host_resolve() && blocks <= 65535;  // one dispatch row of blocks
  run.deepest = 0;
  std::uint32_t drawn[4] = {0, 0, 0, 0};
  if (run.gpu_sum) {
    if (blocks * 4 > batch.scan_blocks_capacity) {
      batch.scan_blocks_capacity = std::max(blocks * 4, batch.scan_blocks_capacity * 3 / 2);
      gl.NamedBufferData(batch.scan_blocks, GLsizeiptr(batch.scan_blocks_capacity), nullptr, GL_DYNAMIC_COPY);
    }
    barrier(GL_SHADER_STORAGE_BARRIER_BIT);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch.offset_buffer);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 11, batch.scan_blocks);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 12, batch.scan_total);
    gl.UseProgram(prefix_sum.id);
    gl.Uniform1ui(prefix_sum.texels, GLuint(run.texels));
    gl.Uniform1ui(prefix_sum.blocks, GLuint(blocks));
    for (int pass = 0; pass < 3; ++pass) {
      gl.Uniform1i(prefix_sum.pass, pass);
      dispatch(pass == 1 ? 1u : GLuint(blocks), 1, 1);
      barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
    const auto t_total = Clock::now();
    std::uint32_t sum = 0;
    read_buffer(batch.scan_total, 0, sizeof sum, &sum);
    read_buffer(batch.command, 0, sizeof drawn, drawn);
    t.readback += ms_since(t_total);
    run.total = sum == 0xffffffffu ? std::numeric_limits<std::size_t>::max() : sum;
  } else {
    run.total = read_batch_counts(run.texels, t);
    run.deepest = batch.deepest;
    const auto t_counts = Clock::now();
    read_buffer(batch.command, 0, sizeof drawn, drawn);
    t.readback += ms_since(t_counts);
  }
  run.selected = drawn[0] / 3 - run.host_entries;  // by the selection pass
}

// The fill pass: every fragment stored at its texel's offset (the counts count again).
void GlImageStage::Impl::fill_batch(const BatchRun& run) {
  if (!run.gpu_sum) {
    upload_buffer(batch.offset_buffer, 0, GLsizeiptr(run.texels * 4), batch.offsets.data());
  }
  ensure_fragments(std::max<std::size_t>(run.total, 1));
  clear_buffer(count_buffer, GLsizeiptr(run.texels * 4));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch.offset_buffer);
  cover_batch_pass(run, false);
  gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
  gl.BindVertexArray(vao);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  // The compute coverage's k-buffer read by the GPU resolve (through buffer textures): its
  // commands submitted first. zink over lavapipe (Mesa 22.3) left the resolve's texel fetches
  // unordered with the fill dispatch's storage writes under any memory barrier (a draw's are
  // ordered by its render pass); a flush orders them, and costs a submission, no wait.
  if (!run.point && compute_coverage(run.largest) && !host_resolve()) gl.Flush();
  check("the batched draws");
}

// A rigid shape's first corner in the resident buffer: copied there (GPU to GPU) from its cached
// buffer (cached_shape(): uploaded the first time the shape is seen) the first time a batch draws
// it.
std::size_t GlImageStage::Impl::resident_base(const std::shared_ptr<const Mesh>& shape, IdMode ids) {
  const auto key = std::make_pair(static_cast<const void*>(shape.get()), ids);
  if (auto it = resident.find(key); it != resident.end() && !it->second.owner.expired()) return it->second.base;
  const CachedShape& cached = cached_shape(shape, ids);
  const std::size_t base = resident_reserve(key, shape, cached.corners);
  if (cached.corners)
    copy_buffer(cached.vbo, resident_buffer, 0, GLintptr(base * sizeof(GpuVertex)),
                GLsizeiptr(cached.corners * sizeof(GpuVertex)));
  check("a rigid shape into the resident buffer");
  return base;
}

// A moving mesh's first corner record in the resident buffer (per corner of each triangle: its
// vertex, 0, 0, its ID), uploaded the first time a batch draws this topology with this ID mode
// (counted in shape_uploads); kept while something holds the topology.
std::size_t GlImageStage::Impl::resident_topology(const MovingMesh& moving, IdMode ids) {
  const auto key = std::make_pair(moving.topology.get(), ids);
  if (auto it = resident.find(key); it != resident.end() && !it->second.owner.expired()) return it->second.base;
  const Mesh& mesh = *moving.source;
  std::vector<std::array<std::uint32_t, 4>> records;
  records.reserve(3 * mesh.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) records.push_back({mesh.triangles[t][k], 0u, 0u, corner_id(mesh, t, k, ids)});
  const std::size_t base = resident_reserve(key, moving.topology, records.size());
  if (!records.empty())
    upload_geometry(resident_buffer, GLintptr(base * sizeof(GpuVertex)), GLsizeiptr(records.size() * sizeof(GpuVertex)),
                    records.data());
  ++shape_uploads;
  check("a moving mesh's triangles into the resident buffer");
  return base;
}

// Where a moving mesh's vertices are in this batch's positions: placed after the meshes met
// before (written by upload_batch()).
std::uint32_t GlImageStage::Impl::moving_positions(const Mesh& mesh) {
  const auto [it, added] = batch.moving_bases.try_emplace(&mesh, std::uint32_t(batch.position_count));
  if (added) {
    batch.moving_order.push_back(&mesh);
    batch.position_count += mesh.vertices.size();
  }
  return it->second;
}

// The batch's moving meshes' vertices into the positions buffer (grown when too small), rounded
// to the nearest floats as they are written through a mapping of the buffer: one pass over the
// doubles, no host copy (the bytes counted as geometry uploaded).
void GlImageStage::Impl::upload_positions() {
  const std::size_t bytes = batch.position_count * 3 * sizeof(float);
  if (bytes == 0) return;
  if (bytes > batch.positions_capacity) {
    batch.positions_capacity = std::max(bytes, batch.positions_capacity * 3 / 2);
    gl.NamedBufferData(batch.positions, GLsizeiptr(batch.positions_capacity), nullptr, GL_STREAM_DRAW);
  }
  const TimedPass pass(timers, GpuPass::transfer);
  auto* out = static_cast<float*>(gl.MapNamedBufferRange(batch.positions, 0, GLsizeiptr(bytes),
                                                        GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
  if (!out) throw GlError("peelcd::gl::GlImageStage: could not map the moving meshes' vertex buffer");
  for (const Mesh* mesh : batch.moving_order)
    for (const Vec3& p : mesh->vertices) {
      out[0] = float(p.x());
      out[1] = float(p.y());
      out[2] = float(p.z());
      out += 3;
    }
  gl.UnmapNamedBuffer(batch.positions);
  count_geometry(bytes);
}

// Room for `corners` resident corners under `key` (held while `owner` lives): its first corner.
// When the buffer is full, the entries still held are moved into a larger one (compaction).
std::size_t GlImageStage::Impl::resident_reserve(const std::pair<const void*, IdMode>& key,
                                                 const std::shared_ptr<const void>& owner, std::size_t corners) {
  resident.erase(key);
  if (resident_used + corners > resident_capacity) {
    std::size_t live = 0;
    for (auto it = resident.begin(); it != resident.end();) {
      if (it->second.owner.expired()) {
        it = resident.erase(it);
      } else {
        live += it->second.corners;
        ++it;
      }
    }
    const std::size_t capacity = std::max({live + corners, resident_capacity * 3 / 2, std::size_t(1024)});
    GLuint grown = 0;
    gl.CreateBuffers(1, &grown);
    gl.NamedBufferData(grown, GLsizeiptr(capacity * sizeof(GpuVertex)), nullptr, GL_STATIC_DRAW);
    std::size_t at = 0;
    for (auto& [k, r] : resident) {
      copy_buffer(resident_buffer, grown, GLintptr(r.base * sizeof(GpuVertex)), GLintptr(at * sizeof(GpuVertex)),
                  GLsizeiptr(r.corners * sizeof(GpuVertex)));
      r.base = at;
      at += r.corners;
    }
    gl.DeleteBuffers(1, &resident_buffer);
    resident_buffer = grown;
    resident_capacity = capacity;
    resident_used = at;
  }
  ResidentShape r;
  r.owner = owner;
  r.base = resident_used;
  r.corners = corners;
  resident_used += corners;
  resident.emplace(key, r);
  return r.base;
}

}  // namespace peelcd::gl
