// Batched conservative views (GlImageStage::peel_batch): the ROI views of a frame packed into one
// k-buffer, view after view, and drawn by one draw call through shaders/conservative.* (PEELCD_BATCH);
// each view's part then resolved on the host (core/kbuffer.cpp, KBuffer::stride). Per triangle,
// a buffer names its view and object; per view, a buffer holds its matrix, the objects' poses,
// its resolution and its first texel. The arithmetic per texel is that of the one-view draw
// (shaders/conservative.*), so a view gives the same layers and PCS either way.
#include "stage_impl.h"

#include <algorithm>
#include <cstring>

namespace peelcd::gl {

void GlImageStage::peel(const PeelJob& job, PeelResult& out, Timings& timings) { impl_->peel_one(job, out, timings); }

void GlImageStage::peel_batch(const PeelJob* jobs, std::size_t count, PeelResult* outs, Timings& timings) {
  Impl& s = *impl_;
  std::size_t i = 0;
  while (i < count) {
    std::size_t end = i;  // a run of conservative views
    while (end < count && jobs[end].conservative) ++end;
    if (end - i < 2 || !s.host_resolve() || !s.options.batch) {
      s.peel_one(jobs[i], outs[i], timings);
      ++i;
      continue;
    }
    while (i < end) i += s.peel_conservative_batch(jobs + i, end - i, outs + i, timings);
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

// One view's record in the views buffer (std430: mat4 clip, mat4 poses[2], ivec4 info).
constexpr std::size_t kViewWords = 16 + 32 + 4;

void put_matrix(std::vector<float>& out, const float* m) { out.insert(out.end(), m, m + 16); }

}  // namespace

std::size_t GlImageStage::Impl::peel_conservative_batch(const PeelJob* jobs, std::size_t count, PeelResult* outs,
                                                        Timings& t) {
  // As many views as one packed k-buffer holds at the current slots (the largest storage block).
  const std::size_t most = std::min(max_storage_block / 16, fetchable());
  std::size_t texels = 0, take = 0, corners_total = 0;
  int largest = 0;
  for (; take < count; ++take) {
    const int n = jobs[take].view.resolution;
    const std::size_t tx = std::size_t(n) * std::size_t(n);
    if ((texels + tx) * slots > most) break;
    texels += tx;
    largest = std::max(largest, n);
    corners_total += 3 * (jobs[take].triangles[0]->size() + jobs[take].triangles[1]->size());
  }
  if (take < 2) {  // one view alone fills a k-buffer: the one-view path (it regrows or gives up)
    peel_one(jobs[0], outs[0], t);
    return 1;
  }

  const auto t0 = Clock::now();
  batch_corners.clear();
  batch_triangle_view.clear();
  batch_ids.clear();
  batch_view_data.clear();
  std::size_t base = 0;
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
      float model[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
      if (rigid) {  // ROI-local from shape-local, composed in double, rounded once (as prepare())
        Eigen::Affine3d m = object.rigid->pose;
        m.translation() -= view.center;
        const Eigen::Matrix4d mm = m.matrix();
        for (int i = 0; i < 16; ++i) model[i] = float(mm(i % 4, i / 4));
      }
      put_matrix(batch_view_data, model);
      const std::vector<std::uint32_t>& tris = *job.triangles[slot];
      for (const std::uint32_t tri : tris) {
        for (int k = 0; k < 3; ++k) {
          const Vec3& p = mesh.vertices[mesh.triangles[tri][k]];
          const Vec3 local = rigid ? p : Vec3(p - view.center);
          batch_corners.push_back({float(local.x()), float(local.y()), float(local.z()), corner_id(mesh, tri, k, job.ids)});
        }
        batch_triangle_view.push_back(std::uint32_t(j) << 1 | std::uint32_t(slot));
        batch_ids.push_back(batch_corners.back().id);  // the provoking (last) corner's ID
      }
      out.triangles_uploaded += tris.size();
    }
    const std::int32_t info[4] = {view.resolution, std::int32_t(base), 0, 0};
    float info_words[4];
    std::memcpy(info_words, info, sizeof info);
    batch_view_data.insert(batch_view_data.end(), info_words, info_words + 4);
    base += std::size_t(view.resolution) * std::size_t(view.resolution);
  }
  const auto upload_buffer = [&](GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes) {
    if (bytes > capacity) {
      capacity = std::max(bytes, capacity * 3 / 2);
      gl.NamedBufferData(buffer, GLsizeiptr(capacity), nullptr, GL_STREAM_DRAW);
    }
    gl.NamedBufferSubData(buffer, 0, GLsizeiptr(bytes), data);
    count_upload(bytes);
  };
  upload_buffer(batch_vbo, batch_vbo_capacity, batch_corners.data(), batch_corners.size() * sizeof(GpuVertex));
  upload_buffer(batch_views, batch_views_capacity, batch_view_data.data(), batch_view_data.size() * sizeof(float));
  upload_buffer(batch_triangles, batch_triangles_capacity, batch_triangle_view.data(),
                batch_triangle_view.size() * sizeof(std::uint32_t));
  t.upload += ms_since(t0);

  const auto t_gpu = Clock::now();
  ensure_bare_fbo(std::max(largest, bare_size));
  ensure_kbuffer(texels, slots);
  const GLuint zero = 0;
  gl.ClearNamedBufferSubData(count_buffer, GL_R32UI, 0, GLsizeiptr(texels * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, count_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, batch_views);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, batch_triangles);
  gl.UseProgram(cons_batch_program);
  gl.Uniform1i(u_cb_viewport, largest);
  gl.Uniform1ui(u_cb_slots, slots);
  gl.Uniform1ui(u_cb_texels, GLuint(texels));
  gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
  gl.Viewport(0, 0, largest, largest);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_CULL_FACE);
  for (int i = 0; i < 6; ++i) gl.Disable(GL_CLIP_DISTANCE0 + i);
  gl.BindVertexArray(vao);
  gl.VertexArrayVertexBuffer(vao, 0, batch_vbo, 0, sizeof(GpuVertex));
  gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(corners_total));
  count_draw();
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  check("the batched conservative draw");

  const auto t_map = Clock::now();
  const auto* counts = static_cast<const std::uint32_t*>(
      gl.MapNamedBufferRange(count_buffer, 0, GLsizeiptr(texels * 4), GL_MAP_READ_BIT));
  const auto* fragments = static_cast<const KFragment*>(
      gl.MapNamedBufferRange(fragment_buffer, 0, GLsizeiptr(texels * slots * sizeof(KFragment)), GL_MAP_READ_BIT));
  const double map_ms = ms_since(t_map);
  count_read(texels * 4);
  count_read(texels * slots * sizeof(KFragment));
  t.readback += map_ms;
  if (!counts || !fragments) {
    if (counts) gl.UnmapNamedBuffer(count_buffer);
    if (fragments) gl.UnmapNamedBuffer(fragment_buffer);
    check("mapping the packed k-buffer");
    throw GlError("peelcd::gl::GlImageStage: mapping the packed k-buffer failed");
  }
  std::uint32_t deepest = 0;
  base = 0;
  for (std::size_t j = 0; j < take; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& out = outs[j];
    const int n = job.view.resolution;
    KBuffer kb;
    kb.counts = counts + base;
    kb.fragments = fragments + base;
    kb.resolution = n;
    kb.slots = slots;
    kb.stride = texels;
    KResolveParams p;
    p.conservative = true;
    p.ids[0] = batch_ids.data();  // keys hold the draw order of the whole batch
    p.ids[1] = batch_ids.data();
    const KResolveResult got = resolver.resolve(kb, p, out.pcs, job.capture ? &out.captured : nullptr);
    deepest = std::max(deepest, got.max_fragments);
    out.layers = int(got.max_layers);
    out.peel_passes = 1;
    out.epsilon_window = 0.0f;
    out.slope = 0.0f;
    if (!out.pcs.empty()) ++out.pcs_readbacks;
    base += std::size_t(n) * std::size_t(n);
  }
  gl.UnmapNamedBuffer(count_buffer);
  gl.UnmapNamedBuffer(fragment_buffer);
  check("the host resolve of the packed k-buffer");
  t.gpu += ms_since(t_gpu) - map_ms;
  outs[0].gl_passes = 1;  // one draw for the batch
  if (deepest > slots) {  // a texel overflowed: more slots and again, or each view on its own
    const std::size_t wanted = std::size_t(deepest) * 5 / 4;
    if (wanted * std::size_t(largest) * std::size_t(largest) <= most) {
      slots = std::uint32_t(wanted);
      return 0;  // the caller calls again from the same view
    }
    for (std::size_t j = 0; j < take; ++j) peel_one(jobs[j], outs[j], t);
  }
  return take;
}

}  // namespace peelcd::gl
