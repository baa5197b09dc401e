// The single-pass peeler (Peeler::abuffer): both objects drawn once into a per-texel k-buffer
// (shaders/abuffer.frag), then the layers and PCS recovered per texel, by a compute pass on the
// GPU (shaders/abuffer_resolve.comp) or on the host (core/image/kbuffer.cpp) where GL runs on the CPU.
#include "stage_impl.h"
#include "peelcd/core/image/conservative.h"
#include "peelcd/core/image/texel.h"

#include <cstring>

#include <algorithm>

namespace peelcd::gl {

// Zeroes the k-buffer's counts and the PCS header for an n x n view and binds the buffers the
// draw and the resolve write (both single-pass peelers).
void GlImageStage::Impl::start_kbuffer(int n, std::uint32_t view_slots) {
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  ensure_bare_fbo(n);
  ensure_kbuffer(texels, view_slots);
  clear_buffer(count_buffer, GLsizeiptr(texels * 4));
  const PcsHeader header{0, pcs_capacity, 0, 0};
  upload_buffer(pcs_buffer, 0, sizeof header, &header);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, count_buffer);
}

// The resolve programs read the k-buffer and the drawn corners (IDs) through buffer textures.
void GlImageStage::Impl::bind_resolve_inputs() {
  gl.BindTextureUnit(0, count_tex);
  gl.BindTextureUnit(1, fragment_tex);
  for (int slot = 0; slot < 2; ++slot) {
    gl.TextureBuffer(corner_tex[slot], GL_RGBA32UI, slot_shape[slot] ? slot_shape[slot]->vbo : vbo[slot]);
    gl.BindTextureUnit(GLuint(2 + slot), corner_tex[slot]);
  }
}

// With the resolve program in use: every layer read back, one dispatch per layer that writes
// only layer k (`u_emit`), appending no PCS (`u_append`).
void GlImageStage::Impl::capture_resolved(int n, int layers, GLint u_append, GLint u_emit, PeelResult& out) {
  const GLuint zero4[4] = {0, 0, 0, 0};
  gl.Uniform1i(u_append, 0);
  ensure_layers(n);
  gl.BindImageTexture(2, layer_tex[0], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32UI);
  for (int k = 0; k < layers; ++k) {
    gl.ClearTexImage(layer_tex[0], 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, zero4);
    gl.Uniform1i(u_emit, k);
    dispatch(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
    barrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    std::vector<std::uint32_t>& texels = out.captured.emplace_back(std::size_t(n) * n * 4);
    read_texture(layer_tex[0], texels);
  }
  check("layer capture");
}

// Returns false if a texel had more fragments than slots or the PCS buffer overflowed (grown;
// the caller peels again). A view whose k-buffer would exceed the largest shader storage block
// is peeled by multi-pass instead (the same layers and PCS).
bool GlImageStage::Impl::peel_single_pass(const PeelJob& job, PeelResult& out, Timings& t) {
  const RoiView& view = job.view;
  const int n = view.resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  // The resolve fetches the corners through buffer textures too.
  const std::size_t fitting = fitting_slots(texels);
  const auto view_slots = std::uint32_t(std::min<std::size_t>(slots, fitting));
  if (view_slots == 0 || std::max(vbo_corners(0), vbo_corners(1)) > fetchable())
    return peel_multipass(job, out, t);
  const auto t_gpu = Clock::now();
  start_kbuffer(n, view_slots);

  gl.UseProgram(abuffer.id);
  set_view_uniforms(abuffer.clip, abuffer.lo, abuffer.hi, view);
  gl.Uniform1i(abuffer.res, n);
  gl.Uniform1ui(abuffer.slots, view_slots);
  gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
  gl.Viewport(0, 0, n, n);
  gl.Disable(GL_DEPTH_TEST);
  gl.Disable(GL_CULL_FACE);
  gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
  for (int i = 0; i < 6; ++i) gl.Enable(GL_CLIP_DISTANCE0 + i);
  gl.BindVertexArray(vao);
  for (int slot = 0; slot < 2; ++slot) {
    gl.Uniform1ui(abuffer.object, GLuint(slot));
    draw(slot, abuffer.model);
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  out.epsilon_window = float(view.world_to_window_depth(job.epsilon));
  out.slope = float(job.slope);
  if (host_resolve())
    return resolve_on_host(job, fitting, view_slots, t_gpu, out, t);
  // The resolve reads what the draw stored through buffer textures (texture fetches).
  barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  ++out.gl_passes;
  check("the k-buffer draw");

  gl.UseProgram(resolve.id);
  bind_resolve_inputs();
  gl.Uniform1f(resolve.eps, out.epsilon_window);
  gl.Uniform1f(resolve.slope, out.slope);
  gl.Uniform1i(resolve.res, n);
  gl.Uniform1ui(resolve.slots, view_slots);
  gl.Uniform1i(resolve.full, job.peel == PeelMode::full);
  gl.Uniform1ui(resolve.first, GLuint(job.first));
  return dispatch_resolve(job, fitting, view_slots, t_gpu, resolve.append, resolve.emit, "the k-buffer resolve", out, t);
}

bool GlImageStage::Impl::dispatch_resolve(const PeelJob& job, std::size_t fitting, std::uint32_t view_slots,
                                          Clock::time_point t_gpu, GLint u_append, GLint u_emit, const char* what,
                                          PeelResult& out, Timings& t) {
  const int n = job.view.resolution;
  gl.Uniform1i(u_append, 1);
  gl.Uniform1i(u_emit, -1);
  dispatch(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  ++out.gl_passes;
  check(what);
  PcsHeader got{};
  read_buffer(pcs_buffer, 0, sizeof got, &got);
  if (got.max_fragments > view_slots) {
    t.gpu += ms_since(t_gpu);
    return regrow(got.max_fragments, fitting, job, out, t);
  }
  if (got.max_fragments > 0) {  // a texel deeper than one invocation resolves: the host resolves
    ++counters->views_host_resolved;
    return resolve_on_host(job, fitting, view_slots, t_gpu, out, t);
  }
  out.layers = int(got.max_layers);
  out.peel_passes = 1;
  out.captured.clear();
  if (job.capture) capture_resolved(n, out.layers, u_append, u_emit, out);
  t.gpu += ms_since(t_gpu);
  return read_pcs(out, t, &got);
}

// A texel had `max_fragments`, more than the k-buffer's slots: grow it (with a quarter to
// spare) and return false (peel again); deeper than any k-buffer that fits (`fitting` slots),
// this view goes to multi-pass (`slots` stays).
bool GlImageStage::Impl::regrow(std::uint32_t max_fragments, std::size_t fitting, const PeelJob& job, PeelResult& out,
                                Timings& t) {
  const std::size_t wanted = std::min<std::size_t>(std::size_t(max_fragments) * 5 / 4, fitting);
  if (wanted < max_fragments && job.conservative) {  // no multi-pass form of intervals
    out.pcs.clear();
    out.captured.clear();
    out.exhaustive = true;
    return true;
  }
  if (wanted < max_fragments) return peel_multipass(job, out, t);
  slots = std::max(slots, std::uint32_t(wanted));
  return false;
}

// The second half of peel_single_pass() with Resolve::host: the k-buffer mapped (host memory on
// a software renderer: no copy) and resolved by core/image/kbuffer.cpp into the PCS.
bool GlImageStage::Impl::resolve_on_host(const PeelJob& job, std::size_t fitting, std::uint32_t view_slots,
                                         Clock::time_point t_gpu, PeelResult& out, Timings& t) {
  const int n = job.view.resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  ++out.gl_passes;
  // Triangle IDs by draw order (gl_VertexID / 3, shaders/peel.vert): the provoking (last)
  // corner's. Arrays: the position in `staging`; a rigid shape: its triangle index.
  const std::uint32_t* ids[2];
  for (int slot = 0; slot < 2; ++slot) {
    if (slot_shape[slot]) {
      ids[slot] = slot_shape[slot]->provoking_ids.data();
      continue;
    }
    std::vector<std::uint32_t>& by_order = ids_by_order[slot];
    by_order.resize(staging[slot].size() / 3);
    for (std::size_t i = 0; i < by_order.size(); ++i) by_order[i] = staging[slot][3 * i + 2].id;
    ids[slot] = by_order.data();
  }
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  const auto t_map = Clock::now();
  const auto* counts = static_cast<const std::uint32_t*>(map_for_reading(count_buffer, texels * 4));
  const auto* fragments =
      static_cast<const KFragment*>(map_for_reading(fragment_buffer, texels * view_slots * sizeof(KFragment)));
  const double map_ms = ms_since(t_map);  // a wait for the draw, then (llvmpipe) no copy
  t.readback += map_ms;
  if (!counts || !fragments) {
    if (counts) gl.UnmapNamedBuffer(count_buffer);
    if (fragments) gl.UnmapNamedBuffer(fragment_buffer);
    check("mapping the k-buffer");
    throw GlError("peelcd::gl::GlImageStage: mapping the k-buffer failed");
  }
  KBuffer kb;
  kb.counts = counts;
  kb.fragments = fragments;
  kb.resolution = n;
  kb.slots = view_slots;
  KResolveParams p;
  p.epsilon_window = out.epsilon_window;
  p.slope = out.slope;
  p.full_peel = job.peel == PeelMode::full;
  p.first_object = std::uint32_t(job.first);
  p.conservative = job.conservative;
  p.ids[0] = ids[0];
  p.ids[1] = ids[1];
  out.pcs.clear();
  out.captured.clear();
  const KResolveResult got = resolver.resolve(kb, p, out.pcs, job.capture ? &out.captured : nullptr);
  gl.UnmapNamedBuffer(count_buffer);
  gl.UnmapNamedBuffer(fragment_buffer);
  check("the host k-buffer resolve");
  t.gpu += ms_since(t_gpu) - map_ms;
  if (got.max_fragments > view_slots) return regrow(got.max_fragments, fitting, job, out, t);
  out.layers = int(got.max_layers);
  out.peel_passes = 1;
  if (!out.pcs.empty()) ++out.pcs_readbacks;  // the PCS reach the CPU (no list to read back here)
  return true;
}

}  // namespace peelcd::gl

namespace peelcd::gl {

// Conservative mode: both objects drawn once through shaders/conservative.{vert,geom,frag} into
// the k-buffer (depth intervals), resolved by shaders/conservative_resolve.comp or on the host.
bool GlImageStage::Impl::peel_conservative(const PeelJob& job, PeelResult& out, Timings& t) {
  const RoiView& view = job.view;
  const int n = view.resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  const std::size_t fitting = fitting_slots(texels);
  const auto view_slots = std::uint32_t(std::min<std::size_t>(slots, fitting));
  if (view_slots == 0 || std::max(vbo_corners(0), vbo_corners(1)) > fetchable()) {
    out.exhaustive = true;  // no k-buffer of this view fits: the detector tests the boxes
    return true;
  }
  const auto t_gpu = Clock::now();
  start_kbuffer(n, view_slots);

  const std::array<float, 16> m = view.clip_from_local();
  float grow_x = 0.0f, grow_z = 0.0f;
  conservative::grow_of(job.grow, view.texel(), 2.0 * view.half_depth, grow_x, grow_z);
  if (compute_coverage(n)) {
    ensure_cover_programs();
    gl.UseProgram(cover.id);
    for (int slot = 0; slot < 2; ++slot) cover_one_view(slot, m, n, view_slots, grow_x, grow_z);
    // The GPU resolve reads the k-buffer through buffer textures: the dispatches submitted first
    // (fill_batch() says why).
    if (!host_resolve()) gl.Flush();
  } else {
    gl.UseProgram(cons.id);
    gl.UniformMatrix4fv(cons.clip, 1, GL_FALSE, m.data());
    gl.Uniform1i(cons.res, n);
    gl.Uniform1ui(cons.slots, view_slots);
    gl.Uniform1f(cons.grow_texels, grow_x);
    gl.Uniform1f(cons.grow_depth, grow_z);
    gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
    gl.Viewport(0, 0, n, n);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_CULL_FACE);
    for (int i = 0; i < 6; ++i) gl.Disable(GL_CLIP_DISTANCE0 + i);  // the intervals clip in depth
    gl.BindVertexArray(vao);
    for (int slot = 0; slot < 2; ++slot) {
      gl.Uniform1ui(cons.object, GLuint(slot));
      draw(slot, cons.model);
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  out.epsilon_window = 0.0f;
  out.slope = 0.0f;
  if (host_resolve())
    return resolve_on_host(job, fitting, view_slots, t_gpu, out, t);
  barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  ++out.gl_passes;
  check("the conservative k-buffer draw");

  gl.UseProgram(cons_resolve.id);
  bind_resolve_inputs();
  gl.Uniform1i(cons_resolve.res, n);
  gl.Uniform1ui(cons_resolve.slots, view_slots);
  return dispatch_resolve(job, fitting, view_slots, t_gpu, cons_resolve.append, cons_resolve.emit, "the conservative resolve", out, t);
}

// The compute path's coverage of one object of a one-view conservative draw (the cover program
// in use): one invocation per triangle the draw would have, its corners read from the buffer the
// draw would have fetched (a rigid shape's through its indices); the view's matrix, resolution,
// slots and growth and the object's pose go in the parameters buffer (not uniforms: zink over
// lavapipe, Mesa 22.3, kept a compute program's earlier uniform values).
void GlImageStage::Impl::cover_one_view(int slot, const std::array<float, 16>& clip, int n, std::uint32_t view_slots,
                                        float grow_x, float grow_z) {
  static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const bool indexed = slot_shape[slot] != nullptr;
  const std::size_t triangles = (indexed ? indices[slot].size() : staging[slot].size()) / 3;
  if (triangles == 0) return;
  const std::size_t groups = (triangles + 63) / 64;
  const std::size_t gx = std::min<std::size_t>(groups, 65535), gy = (groups + gx - 1) / gx;
  std::uint32_t params[40];
  std::memcpy(params, indexed ? slot_model[slot].data() : identity, 64);
  std::memcpy(params + 16, clip.data(), 64);
  const std::uint32_t words[8] = {std::uint32_t(n), view_slots, std::uint32_t(slot), std::uint32_t(triangles),
                                  indexed ? 1u : 0u, std::uint32_t(gx * 64), texel::bits_of(grow_x),
                                  texel::bits_of(grow_z)};
  std::memcpy(params + 32, words, sizeof words);
  // Each object its own 256 bytes (an offset every implementation aligns storage buffers to):
  // the second upload does not overwrite what the first dispatch reads.
  const GLintptr at = GLintptr(slot) * 256;
  upload_buffer(cover_params, at, sizeof params, params);
  const GLuint corners = indexed ? slot_shape[slot]->vbo : vbo[slot];
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 18, corners);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 19, indexed ? ibo[slot] : corners);
  gl.BindBufferRange(GL_SHADER_STORAGE_BUFFER, 20, cover_params, at, sizeof params);
  dispatch(GLuint(gx), GLuint(gy), 1, GpuPass::cover);
}

}  // namespace peelcd::gl
