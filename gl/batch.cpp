// Batched views (GlImageStage::peel_batch): the ROI views of a frame packed into one compact
// k-buffer and drawn through shaders/conservative.* (conservative views) or shaders/peel.vert and
// abuffer.frag (point-sampled views, the single-pass peeler's), with PEELCD_BATCH. Rigid shapes are
// resident (one buffer, each shape copied there once); per view and rigid object a job goes to
// the selection passes (shaders/batch_select.comp), which append the triangles reaching the
// ROI box and the view's contact region to the draw's entries; deforming objects' triangles
// come from the host (their corners uploaded per frame). A count pass and a fill pass (indirect draws over the entries) fill the
// k-buffer; each view's part is then resolved on the host (core/kbuffer.cpp) or by one dispatch
// (shaders/conservative_batch_resolve.comp, shaders/abuffer_resolve.comp). Per view, a buffer
// holds its matrix, the objects' poses, its resolution, its first texel, its ROI box and, point
// sampled, its PCS threshold, slope and peel mode (shaders/batch.inc). The arithmetic per texel is
// that of the one-view draw, so with the host's selection (GlOptions::gpu_select false, and views
// capturing layers) a view gives the same layers and PCS either way (a point-sampled view smaller
// than the batch's largest is placed by one more scaling: its samples may differ in the last bit).
#include "stage_impl.h"
#include "peelcd/core/texel.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace peelcd::gl {

void GlImageStage::peel(const PeelJob& job, PeelResult& out, Timings& timings) { impl_->peel_one(job, out, timings); }

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
    if (end - i < 2 || !s.options.batch) {
      s.peel_one(jobs[i], outs[i], timings);
      ++i;
      continue;
    }
    while (i < end) i += s.peel_batched_views(jobs + i, end - i, outs + i, timings);
  }
}

void GlImageStage::Impl::peel_one(const PeelJob& job, PeelResult& out, Timings& timings) {
  out.clear();
  const auto t0 = Clock::now();
  shape_uploads = 0;
  for (int slot = 0; slot < 2; ++slot) prepare(*job.objects[slot], job.view, *job.triangles[slot], job.ids, slot);
  upload(0);
  upload(1);
  timings.upload += ms_since(t0);
  for (int slot = 0; slot < 2; ++slot)
    (slot_shape[slot] ? out.triangles_indexed : out.triangles_uploaded) += corners(slot) / 3;
  out.shape_uploads = shape_uploads;
  if (job.conservative) {  // intervals need every fragment at once: the k-buffer
    while (!peel_conservative(job, out, timings)) {
    }
  } else if (options.peeler == Peeler::abuffer) {
    while (!peel_single_pass(job, out, timings)) {
    }
  } else {
    while (!peel_multipass(job, out, timings)) {
    }
  }
}

namespace {

// One view's record in the views buffer (shaders/batch.inc, std430: mat4 clip, mat4 poses[2],
// ivec4 info, vec4 half_box, vec4 box_lo, vec4 box_hi).
constexpr std::size_t kViewWords = 16 + 32 + 4 + 4 + 4 + 4;

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

std::size_t GlImageStage::Impl::peel_batched_views(const PeelJob* jobs, std::size_t count, PeelResult* outs,
                                                   Timings& t) {
  const bool point = !jobs[0].conservative;  // every job of the run is alike
  // As many views as one packed k-buffer holds at the current slots (the largest storage block).
  const std::size_t most = std::min(max_storage_block / 16, fetchable());
  std::size_t texels = 0, take = 0;
  int largest = 0;
  for (; take < count; ++take) {
    const int n = jobs[take].view.resolution;
    const std::size_t tx = std::size_t(n) * std::size_t(n);
    if (texels + tx > most) break;
    texels += tx;
    largest = std::max(largest, n);
  }
  if (take < 2) {  // one view alone fills the counts: the one-view path
    peel_one(jobs[0], outs[0], t);
    return 1;
  }

  const auto t0 = Clock::now();
  batch_corners.clear();
  batch_entry_data.clear();
  batch_job_data.clear();
  batch_ids.clear();
  batch_view_data.clear();
  batch_view_data.reserve(take * kViewWords);
  batch_region_data.clear();
  std::size_t base = 0, invocations = 0;
  shape_uploads = 0;  // the batch's, reported on its first view
  // Every rigid shape of the batch resident first: adding one may move the others (compaction),
  // so their first corners are read only after all are in.
  for (std::size_t j = 0; j < take; ++j)
    for (int slot = 0; slot < 2; ++slot) {
      const Object& object = *jobs[j].objects[slot];
      if (object.rigid && object.rigid->shape) resident_base(object.rigid->shape, jobs[j].ids);
    }
  for (std::size_t j = 0; j < take; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& out = outs[j];
    out.clear();
    const RoiView& view = job.view;
    const std::array<float, 16> clip = view.clip_from_local();
    put_matrix(batch_view_data, clip.data());
    for (int slot = 0; slot < 2; ++slot) {
      const Object& object = *job.objects[slot];
      const bool rigid = object.rigid && object.rigid->shape;
      const Mesh& mesh = rigid ? *object.rigid->shape : object.mesh;
      const std::uint32_t view_object = std::uint32_t(j) << 1 | std::uint32_t(slot);
      float model[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
      if (rigid) {  // ROI-local from shape-local, composed in double, rounded once (as prepare())
        Eigen::Affine3d m = object.rigid->pose;
        m.translation() -= view.center;
        const Eigen::Matrix4d mm = m.matrix();
        for (int i = 0; i < 16; ++i) model[i] = float(mm(i % 4, i / 4));
      }
      put_matrix(batch_view_data, model);
      const std::vector<std::uint32_t>& tris = *job.triangles[slot];
      // The object's region in the view (the selection's contact-region round): empty, for the
      // selection to merge its triangles' boxes into; everything, for the host's selection of a
      // rigid object (its ROI-local corners are the GPU's to compute); the box of the corners
      // uploaded, for a deforming object.
      constexpr float inf = std::numeric_limits<float>::infinity();
      if (rigid) {
        const std::size_t first = resident_base(object.rigid->shape, job.ids);
        if (options.gpu_select && !job.capture) {  // the selection pass picks its triangles
          if (!mesh.triangles.empty())
            batch_job_data.push_back({std::uint32_t(first), std::uint32_t(mesh.triangles.size()), view_object,
                                      std::uint32_t(invocations)});
          invocations += mesh.triangles.size();
          put_region(batch_region_data, Eigen::Vector3f::Constant(inf), Eigen::Vector3f::Constant(-inf));
          continue;
        }
        put_region(batch_region_data, Eigen::Vector3f::Constant(-inf), Eigen::Vector3f::Constant(inf));
        for (const std::uint32_t tri : tris) {  // the host's selection, from the resident corners
          batch_entry_data.push_back({std::uint32_t(first + 3 * std::size_t(tri)), view_object,
                                      corner_id(mesh, tri, 2, job.ids), 0u});
          batch_ids.push_back(batch_entry_data.back()[2]);
        }
        out.triangles_indexed += tris.size();
        continue;
      }
      Eigen::Vector3f lo = Eigen::Vector3f::Constant(inf), hi = Eigen::Vector3f::Constant(-inf);
      for (const std::uint32_t tri : tris) {
        const std::uint32_t corner = std::uint32_t(batch_corners.size());
        for (int k = 0; k < 3; ++k) {
          const Vec3 local = mesh.vertices[mesh.triangles[tri][k]] - view.center;
          batch_corners.push_back({float(local.x()), float(local.y()), float(local.z()), corner_id(mesh, tri, k, job.ids)});
          const Eigen::Vector3f p(batch_corners.back().x, batch_corners.back().y, batch_corners.back().z);
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
        batch_entry_data.push_back({0x80000000u | corner, view_object, batch_corners.back().id, 0u});
        batch_ids.push_back(batch_corners.back().id);
      }
      put_region(batch_region_data, lo, hi);
      out.triangles_uploaded += tris.size();
    }
    const std::int32_t flags = point ? std::int32_t(job.peel == PeelMode::full) << 1 | std::int32_t(job.first & 1) : 0;
    const std::int32_t info[4] = {view.resolution, std::int32_t(base), flags, 0};
    float info_words[4];
    std::memcpy(info_words, info, sizeof info);
    batch_view_data.insert(batch_view_data.end(), info_words, info_words + 4);
    const Vec3 half = 0.5 * view.box.extent();
    batch_view_data.insert(batch_view_data.end(), {float(half.x()), float(half.y()), float(half.z()), 0.0f});
    // The clip planes and the PCS test as the one-view point-sampled draw has them.
    out.epsilon_window = point ? float(view.world_to_window_depth(job.epsilon)) : 0.0f;
    out.slope = point ? float(job.slope) : 0.0f;
    const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
    batch_view_data.insert(batch_view_data.end(), {float(lo.x()), float(lo.y()), float(lo.z()), out.epsilon_window});
    batch_view_data.insert(batch_view_data.end(), {float(hi.x()), float(hi.y()), float(hi.z()), out.slope});
    base += std::size_t(view.resolution) * std::size_t(view.resolution);
  }
  outs[0].shape_uploads = shape_uploads;
  const std::size_t host_entries = batch_entry_data.size();
  if (std::max(host_entries + invocations, batch_corners.size()) >= 0x7fffffffu / 3)
    throw GlError("peelcd::gl::GlImageStage: a batch of " + std::to_string(host_entries + invocations) +
                  " triangles is more than a draw's order holds (2^31 / 3)");
  const auto upload_buffer = [&](GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes,
                                 std::size_t reserve, bool geometry) {
    if (std::max(bytes, reserve) > capacity || capacity == 0) {
      capacity = std::max({bytes, reserve, capacity * 3 / 2, std::size_t(16)});
      gl.NamedBufferData(buffer, GLsizeiptr(capacity), nullptr, GL_STREAM_DRAW);
    }
    if (bytes == 0) return;
    gl.NamedBufferSubData(buffer, 0, GLsizeiptr(bytes), data);
    geometry ? count_geometry(bytes) : count_upload(bytes);
  };
  constexpr std::size_t kEntry = 4 * sizeof(std::uint32_t);
  upload_buffer(batch_frame, batch_frame_capacity, batch_corners.data(), batch_corners.size() * sizeof(GpuVertex), 0, true);
  upload_buffer(batch_views, batch_views_capacity, batch_view_data.data(), batch_view_data.size() * sizeof(float), 0, false);
  // The entries: the host's first, room after them for every triangle the selection may keep.
  upload_buffer(batch_entries, batch_entries_capacity, batch_entry_data.data(), host_entries * kEntry,
                (host_entries + invocations) * kEntry, true);
  upload_buffer(batch_jobs, batch_jobs_capacity, batch_job_data.data(), batch_job_data.size() * kEntry, 0, false);
  const std::uint32_t command[4] = {std::uint32_t(3 * host_entries), 1u, 0u, 0u};
  gl.NamedBufferSubData(batch_command, 0, sizeof command, command);
  count_upload(sizeof command);
  t.upload += ms_since(t0);

  const auto t_gpu = Clock::now();
  ensure_bare_fbo(std::max(largest, bare_size));
  ensure_kbuffer(texels, 1);  // the counts; the fragments are sized by the count pass below
  const GLuint zero = 0;
  gl.ClearNamedBufferSubData(count_buffer, GL_R32UI, 0, GLsizeiptr(texels * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, count_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, batch_views);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, batch_entries);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, resident_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, batch_frame);
  if (invocations) {
    // 0. The selection pass: rigid objects' triangles in each view's ROI box staged, their
    // objects' regions merged; then its contact-region round: those that reach the view's
    // region appended to the entries (shaders/batch_select.comp).
    upload_buffer(batch_regions, batch_regions_capacity, batch_region_data.data(),
                  batch_region_data.size() * sizeof(std::uint32_t), 0, false);
    upload_buffer(batch_staged, batch_staged_capacity, nullptr, 0, (invocations + 1) * kEntry, false);
    const std::uint32_t staged_header[4] = {0, 0, 0, 0};
    gl.NamedBufferSubData(batch_staged, 0, sizeof staged_header, staged_header);
    count_upload(sizeof staged_header);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, batch_jobs);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 10, batch_command);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 13, batch_staged);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 14, batch_regions);
    gl.UseProgram(select_program);
    const std::size_t groups = (invocations + 63) / 64;
    const std::size_t gx = std::min<std::size_t>(groups, 65535), gy = (groups + gx - 1) / gx;
    gl.Uniform1ui(u_sel_jobs, GLuint(batch_job_data.size()));
    gl.Uniform1ui(u_sel_invocations, GLuint(invocations));
    gl.Uniform1ui(u_sel_row, GLuint(gx * 64));
    for (int pass = 0; pass < 2; ++pass) {
      gl.Uniform1i(u_sel_pass, pass);
      gl.DispatchCompute(GLuint(gx), GLuint(gy), 1);
      count_dispatch();
      gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    }
  }
  gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, batch_command);
  gl.UseProgram(point ? point_batch_program : cons_batch_program);
  const GLint u_count_only = point ? u_pb_count_only : u_cb_count_only;
  gl.Uniform1i(point ? u_pb_viewport : u_cb_viewport, largest);
  gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
  gl.Viewport(0, 0, largest, largest);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_CULL_FACE);
  gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
  // Point sampling clips to the ROI box; the conservative intervals clip in depth themselves.
  for (int i = 0; i < 6; ++i) point ? gl.Enable(GL_CLIP_DISTANCE0 + i) : gl.Disable(GL_CLIP_DISTANCE0 + i);
  gl.BindVertexArray(batch_vao);
  // 1. The count pass: each texel's fragments counted, nothing stored.
  gl.Uniform1i(u_count_only, 1);
  gl.DrawArraysIndirect(GL_TRIANGLES, nullptr);
  count_draw();
  gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  // 2. The counts into offsets, the k-buffer sized to hold them all; the triangles drawn (the
  // command's count). The host resolve reads the counts anyway: a prefix sum on the host, the
  // offsets uploaded. The GPU resolve: the prefix sum on the GPU (shaders/prefix_sum.comp), only
  // the total read back.
  const std::size_t offset_bytes = texels * 4;
  if (offset_bytes > batch_offsets_capacity) {
    batch_offsets_capacity = std::max(offset_bytes, batch_offsets_capacity * 3 / 2);
    gl.NamedBufferData(batch_offset_buffer, GLsizeiptr(batch_offsets_capacity), nullptr, GL_DYNAMIC_COPY);
  }
  const std::size_t blocks = (texels + 1023) / 1024;
  const bool gpu_sum = !host_resolve() && blocks <= 65535;  // one dispatch row of blocks
  std::size_t total = 0;
  std::uint32_t deepest = 0;
  std::uint32_t drawn[4] = {0, 0, 0, 0};
  if (gpu_sum) {
    if (blocks * 4 > scan_blocks_capacity) {
      scan_blocks_capacity = std::max(blocks * 4, scan_blocks_capacity * 3 / 2);
      gl.NamedBufferData(scan_blocks, GLsizeiptr(scan_blocks_capacity), nullptr, GL_DYNAMIC_COPY);
    }
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch_offset_buffer);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 11, scan_blocks);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 12, scan_total);
    gl.UseProgram(prefix_sum_program);
    gl.Uniform1ui(u_ps_texels, GLuint(texels));
    gl.Uniform1ui(u_ps_blocks, GLuint(blocks));
    for (int pass = 0; pass < 3; ++pass) {
      gl.Uniform1i(u_ps_pass, pass);
      gl.DispatchCompute(pass == 1 ? 1u : GLuint(blocks), 1, 1);
      count_dispatch();
      gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
    const auto t_total = Clock::now();
    std::uint32_t sum = 0;
    gl.GetNamedBufferSubData(scan_total, 0, sizeof sum, &sum);
    count_read(sizeof sum);
    gl.GetNamedBufferSubData(batch_command, 0, sizeof drawn, drawn);
    count_read(sizeof drawn);
    t.readback += ms_since(t_total);
    total = sum == 0xffffffffu ? std::numeric_limits<std::size_t>::max() : sum;
    gl.UseProgram(point ? point_batch_program : cons_batch_program);
  } else {
    total = read_batch_counts(texels, t);
    deepest = batch_deepest;
    const auto t_counts = Clock::now();
    gl.GetNamedBufferSubData(batch_command, 0, sizeof drawn, drawn);
    count_read(sizeof drawn);
    t.readback += ms_since(t_counts);
  }
  const std::size_t selected = drawn[0] / 3 - host_entries;  // by the selection pass
  outs[0].triangles_indexed += selected;
  if (total > most) {  // more fragments than one buffer holds: each view on its own
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    gl.BindVertexArray(vao);
    for (std::size_t j = 0; j < take; ++j) peel_one(jobs[j], outs[j], t);
    return take;
  }
  if (!gpu_sum) {
    gl.NamedBufferSubData(batch_offset_buffer, 0, GLsizeiptr(offset_bytes), batch_offsets.data());
    count_upload(offset_bytes);
  }
  ensure_fragments(std::max<std::size_t>(total, 1));
  // 3. The fill pass: every fragment stored at its texel's offset (the counts count again).
  gl.ClearNamedBufferSubData(count_buffer, GL_R32UI, 0, GLsizeiptr(texels * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch_offset_buffer);
  gl.Uniform1i(u_count_only, 0);
  gl.DrawArraysIndirect(GL_TRIANGLES, nullptr);
  count_draw();
  gl.BindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
  gl.BindVertexArray(vao);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  check("the batched draws");

  if (!host_resolve()) {
    if (resolve_batch_on_gpu(take, texels, point, outs, t)) {
      t.gpu += ms_since(t_gpu);
      outs[0].gl_passes = 2;  // the count and fill draws for the batch
      return take;
    }
    // A texel deeper than the GPU resolve takes (point sampling: PEELCD_GPU_RESOLVE_DEPTH
    // fragments): the batch resolved on the host instead, said in views_host_resolved.
    counters->views_host_resolved += take;
    for (std::size_t j = 0; j < take; ++j) outs[j].pcs.clear();
    if (gpu_sum) {
      read_batch_counts(texels, t);
      deepest = batch_deepest;
    }
  }
  if (selected) {  // the selection's entries: their IDs, by draw order
    const auto t_entries = Clock::now();
    batch_entry_data.resize(host_entries + selected);
    gl.GetNamedBufferSubData(batch_entries, GLintptr(host_entries * kEntry), GLsizeiptr(selected * kEntry),
                             batch_entry_data.data() + host_entries);
    count_read(selected * kEntry);
    t.readback += ms_since(t_entries);
    for (std::size_t k = host_entries; k < batch_entry_data.size(); ++k) batch_ids.push_back(batch_entry_data[k][2]);
  }
  const auto t_map = Clock::now();
  const auto* fragments = static_cast<const KFragment*>(
      gl.MapNamedBufferRange(fragment_buffer, 0, GLsizeiptr(total * sizeof(KFragment)), GL_MAP_READ_BIT));
  const double map_ms = ms_since(t_map);
  count_read(total * sizeof(KFragment));
  t.readback += map_ms;
  if (!fragments && total) {
    check("mapping the packed k-buffer");
    throw GlError("peelcd::gl::GlImageStage: mapping the packed k-buffer failed");
  }
  base = 0;
  for (std::size_t j = 0; j < take; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& out = outs[j];
    const int n = job.view.resolution;
    KBuffer kb;
    kb.counts = batch_counts.data() + base;
    kb.fragments = fragments;
    kb.offsets = batch_offsets.data() + base;
    kb.resolution = n;
    kb.slots = deepest;
    KResolveParams p;
    p.conservative = !point;
    p.epsilon_window = out.epsilon_window;
    p.slope = out.slope;
    p.full_peel = job.peel == PeelMode::full;
    p.first_object = std::uint32_t(job.first);
    p.ids[0] = batch_ids.data();  // keys hold the draw order of the whole batch
    p.ids[1] = batch_ids.data();
    const KResolveResult got = resolver.resolve(kb, p, out.pcs, job.capture ? &out.captured : nullptr);
    out.layers = int(got.max_layers);
    out.peel_passes = 1;
    if (!out.pcs.empty()) ++out.pcs_readbacks;
    base += std::size_t(n) * std::size_t(n);
  }
  if (fragments) gl.UnmapNamedBuffer(fragment_buffer);
  check("the host resolve of the packed k-buffer");
  t.gpu += ms_since(t_gpu) - map_ms;
  outs[0].gl_passes = 2;  // the count and fill draws for the batch
  return take;
}

// A rigid shape's first corner in the resident buffer: copied there (GPU to GPU) from its cached
// buffer (cached_shape(): uploaded the first time the shape is seen) the first time a batch draws
// it. When the buffer is full, the shapes still held are moved into a larger one.
std::size_t GlImageStage::Impl::resident_base(const std::shared_ptr<const Mesh>& shape, IdMode ids) {
  const auto key = std::make_pair(shape.get(), ids);
  if (auto it = resident.find(key); it != resident.end() && !it->second.owner.expired()) return it->second.base;
  const CachedShape& cached = cached_shape(shape, ids);
  const std::size_t corners = cached.corners;
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
      gl.CopyNamedBufferSubData(resident_buffer, grown, GLintptr(r.base * sizeof(GpuVertex)),
                                GLintptr(at * sizeof(GpuVertex)), GLsizeiptr(r.corners * sizeof(GpuVertex)));
      r.base = at;
      at += r.corners;
    }
    gl.DeleteBuffers(1, &resident_buffer);
    resident_buffer = grown;
    resident_capacity = capacity;
    resident_used = at;
  }
  if (corners)
    gl.CopyNamedBufferSubData(cached.vbo, resident_buffer, 0, GLintptr(resident_used * sizeof(GpuVertex)),
                              GLsizeiptr(corners * sizeof(GpuVertex)));
  ResidentShape r;
  r.owner = shape;
  r.base = resident_used;
  r.corners = corners;
  resident_used += corners;
  check("a rigid shape into the resident buffer");
  return resident.emplace(key, r).first->second.base;
}

// The count pass's counts read back into batch_counts, their prefix sums into batch_offsets (the
// host resolve's; uploaded by the caller for the fill pass), the deepest texel's count into
// batch_deepest; returns the total.
std::size_t GlImageStage::Impl::read_batch_counts(std::size_t texels, Timings& t) {
  const auto t_counts = Clock::now();
  batch_counts.resize(texels);
  gl.GetNamedBufferSubData(count_buffer, 0, GLsizeiptr(texels * 4), batch_counts.data());
  count_read(texels * 4);
  t.readback += ms_since(t_counts);
  batch_offsets.resize(texels);
  std::size_t total = 0;
  batch_deepest = 0;
  for (std::size_t k = 0; k < texels; ++k) {
    batch_offsets[k] = std::uint32_t(std::min<std::size_t>(total, 0xffffffffu));
    total += batch_counts[k];
    batch_deepest = std::max(batch_deepest, batch_counts[k]);
  }
  return total;
}

// The deep texels' rows (shaders/conservative_batch_resolve.comp with PEELCD_DEEP): a work group
// per row and block of fragments, rows in dispatches of at most 65535 work groups wide.
void GlImageStage::Impl::dispatch_deep_rows(const DeepHeader& deep, std::size_t texels) {
  gl.UseProgram(cons_deep_program);
  gl.Uniform1ui(u_cd_texels, GLuint(texels));
  for (std::size_t base = 0; base < deep.row_count; base += 65535) {
    gl.Uniform1ui(u_cd_row_base, GLuint(base));
    gl.DispatchCompute(GLuint(std::min<std::size_t>(deep.row_count - base, 65535)), deep.max_blocks, 1);
    count_dispatch();
  }
  gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  gl.UseProgram(cons_batch_resolve_program);
}

bool GlImageStage::Impl::resolve_batch_on_gpu(std::size_t take, std::size_t texels, bool point, PeelResult* outs,
                                              Timings& t) {
  // Per-view depths, zeroed; the PCS header reset; one dispatch over every texel.
  const std::size_t layer_bytes = take * sizeof(std::uint32_t);
  if (layer_bytes > batch_layers_capacity) {
    batch_layers_capacity = std::max(layer_bytes, batch_layers_capacity * 3 / 2);
    gl.NamedBufferData(batch_layers, GLsizeiptr(batch_layers_capacity), nullptr, GL_DYNAMIC_READ);
  }
  const GLuint zero = 0;
  gl.ClearNamedBufferSubData(batch_layers, GL_R32UI, 0, GLsizeiptr(layer_bytes), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, batch_entries);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, batch_layers);
  gl.BindTextureUnit(0, count_tex);
  gl.BindTextureUnit(1, fragment_tex);
  gl.UseProgram(point ? point_batch_resolve_program : cons_batch_resolve_program);
  gl.Uniform1ui(point ? u_pbr_texels : u_cbr_texels, GLuint(texels));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch_offset_buffer);
  if (!point && deep_rows_capacity == 0) {
    deep_rows_capacity = 4096;
    gl.NamedBufferData(deep_rows, GLsizeiptr(sizeof(DeepHeader) + deep_rows_capacity * 8), nullptr, GL_DYNAMIC_COPY);
  }
  if (!point) gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, deep_rows);
  PcsHeader got{};
  DeepHeader deep{};
  for (;;) {  // the list's pairs are 16 bytes here (IDs and view): half as many fit
    const PcsHeader header{0, pcs_capacity / 2, 0, 0};
    gl.NamedBufferSubData(pcs_buffer, 0, sizeof header, &header);
    count_upload(sizeof header);
    if (!point) {
      const DeepHeader empty{0, std::uint32_t(deep_rows_capacity), 0, 0};
      gl.NamedBufferSubData(deep_rows, 0, sizeof empty, &empty);
      count_upload(sizeof empty);
    }
    gl.DispatchCompute(GLuint((texels + 63) / 64), 1, 1);
    count_dispatch();
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    const auto t_read = Clock::now();
    gl.GetNamedBufferSubData(pcs_buffer, 0, sizeof got, &got);
    count_read(sizeof got);
    t.readback += ms_since(t_read);
    if (got.max_fragments) return false;  // a texel deeper than this resolve takes
    // Conservative: texels deeper than PEELCD_GPU_RESOLVE_DEPTH left rows for the second program
    // (the deepest texel's count, max_layers, says whether any did: no read otherwise).
    if (!point && got.max_layers > PEELCD_GPU_RESOLVE_DEPTH) {
      const auto t_deep = Clock::now();
      gl.GetNamedBufferSubData(deep_rows, 0, sizeof deep, &deep);
      count_read(sizeof deep);
      t.readback += ms_since(t_deep);
      if (deep.row_count > deep_rows_capacity) {  // larger, and the dispatch again
        deep_rows_capacity = std::size_t(deep.row_count) * 3 / 2;
        gl.NamedBufferData(deep_rows, GLsizeiptr(sizeof(DeepHeader) + deep_rows_capacity * 8), nullptr,
                           GL_DYNAMIC_COPY);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, deep_rows);
        continue;
      }
      dispatch_deep_rows(deep, texels);
      const auto t_again = Clock::now();
      gl.GetNamedBufferSubData(pcs_buffer, 0, sizeof got, &got);
      count_read(sizeof got);
      t.readback += ms_since(t_again);
    }
    if (got.count <= pcs_capacity / 2) break;
    grow_pcs(2 * (got.count + got.count / 2));  // the list did not fit: larger, and the dispatch again
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
  }
  counters->deep_texels += deep.deep_texels;
  const auto t_read = Clock::now();
  batch_view_layers.resize(take);
  gl.GetNamedBufferSubData(batch_layers, 0, GLsizeiptr(layer_bytes), batch_view_layers.data());
  count_read(layer_bytes);
  batch_pairs.resize(std::size_t(got.count) * 4);
  if (got.count) {
    gl.GetNamedBufferSubData(pcs_buffer, sizeof(PcsHeader), GLsizeiptr(got.count) * 16, batch_pairs.data());
    count_read(std::size_t(got.count) * 16);
  }
  t.readback += ms_since(t_read);
  check("the GPU resolve of the packed k-buffer");
  for (std::size_t k = 0; k < got.count; ++k)  // ID of A's, ID of B's, the view
    outs[batch_pairs[4 * k + 2]].pcs.push_back(IdPair{batch_pairs[4 * k], batch_pairs[4 * k + 1]});
  for (std::size_t j = 0; j < take; ++j) {
    PeelResult& out = outs[j];
    out.layers = int(batch_view_layers[j]);
    out.peel_passes = 1;
    if (!out.pcs.empty()) ++out.pcs_readbacks;
  }
  return true;
}

}  // namespace peelcd::gl
