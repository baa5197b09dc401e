// The multi-pass peeler (Peeler::multipass, the paper's way): one draw per logical layer with a
// strict depth test against the previous layer (shaders/peel.frag), the PCS of each adjacent
// couple appended on the GPU (shaders/pcs.comp), until an occlusion query sees no sample.
#include "stage_impl.h"

namespace peelcd::gl {

bool GlImageStage::Impl::peel_multipass(const PeelJob& job, PeelResult& out, Timings& t) {
  const auto t_gpu = Clock::now();
  const RoiView& view = job.view;
  const int n = view.resolution;
  ensure_layers(n);
  const PcsHeader header{0, pcs_capacity, 0, 0};
  upload_buffer(pcs_buffer, 0, sizeof header, &header);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);

  gl.UseProgram(peel.id);
  set_view_uniforms(peel.clip, peel.box_lo, peel.box_hi, view);
  gl.Uniform1ui(peel.rank_flip, job.peel == PeelMode::full ? 0u : GLuint(job.first));
  gl.UseProgram(pcs.id);
  out.epsilon_window = float(view.world_to_window_depth(job.epsilon));
  out.slope = float(job.slope);
  gl.Uniform1f(pcs.eps, out.epsilon_window);
  gl.Uniform1f(pcs.slope, out.slope);
  gl.Uniform1i(pcs.track, job.peel == PeelMode::full);
  if (job.peel == PeelMode::full) {
    gl.ClearTexImage(run_tex, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, nullptr);
    gl.BindImageTexture(0, run_tex, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32UI);
  }
  gl.Uniform1i(pcs.res, n);

  gl.Viewport(0, 0, n, n);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.Disable(GL_CULL_FACE);
  gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
  for (int i = 0; i < 6; ++i) gl.Enable(GL_CLIP_DISTANCE0 + i);
  gl.BindVertexArray(vao);

  const GLuint zero[4] = {0, 0, 0, 0};
  const GLfloat far_depth = 1.0f;
  out.layers = 0;
  out.peel_passes = 0;
  out.captured.clear();  // a rerun after a PCS overflow starts over
  for (int k = 0; k < kMaxPasses; ++k) {
    const int cur = k & 1, prev = cur ^ 1;
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo[cur]);
    gl.ClearBufferuiv(GL_COLOR, 0, zero);
    gl.ClearBufferfv(GL_DEPTH, 0, &far_depth);
    gl.UseProgram(peel.id);
    gl.Uniform1i(peel.has_prev, k > 0);
    gl.BindTextureUnit(0, layer_tex[prev]);
    gl.BeginQuery(GL_ANY_SAMPLES_PASSED, query);
    for (int i = 0; i < 2; ++i) {
      // Alternate: one object per pass, starting with `first`. Full: both, every pass.
      const int slot = job.peel == PeelMode::full ? i : (job.first + k) & 1;
      if (job.peel == PeelMode::alternate && i == 1) break;
      gl.Uniform1ui(peel.object, GLuint(slot));
      draw(slot, peel.model);
    }
    gl.EndQuery(GL_ANY_SAMPLES_PASSED);
    ++out.peel_passes;
    ++out.gl_passes;
    check("a peel pass");
    GLuint any = 0;
    {
      const GlWait wait(wait_ms);
      gl.GetQueryObjectuiv(query, GL_QUERY_RESULT, &any);
      count_read(sizeof any);
    }
    if (!any) break;  // the whole ROI ended
    ++out.layers;
    if (job.capture) {
      std::vector<std::uint32_t>& texels = out.captured.emplace_back(std::size_t(n) * n * 4);
      read_texture(layer_tex[cur], texels);
      check("layer capture");
    }
    if (k == 0) continue;
    gl.UseProgram(pcs.id);
    gl.BindTextureUnit(0, layer_tex[prev]);
    gl.BindTextureUnit(1, layer_tex[cur]);
    dispatch(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
    // The next dispatch reads run_start and appends to the same buffer.
    barrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    ++out.gl_passes;
    check("a PCS pass");
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  t.gpu += ms_since(t_gpu);
  return read_pcs(out, t);
}

bool GlImageStage::Impl::read_pcs(PeelResult& out, Timings& t, const PcsHeader* header) {
  const auto t_read = Clock::now();
  PcsHeader got{};
  if (header)
    got = *header;
  else {
    read_buffer(pcs_buffer, 0, sizeof got, &got);
  }
  if (got.count > pcs_capacity) {
    grow_pcs(got.count + got.count / 2);
    t.readback += ms_since(t_read);
    return false;
  }
  out.pcs.resize(got.count);
  if (got.count) {
    read_buffer(pcs_buffer, sizeof(PcsHeader), GLsizeiptr(got.count) * 8, out.pcs.data());
    ++out.pcs_readbacks;
  }
  check("PCS readback");
  t.readback += ms_since(t_read);
  return true;
}

}  // namespace peelcd::gl
