// Loading GL through the context, compiling and linking the programs, checking errors.
#include "stage_impl.h"

#include <algorithm>
#include <sstream>

namespace peelcd::gl {

GlImageStage::Impl::Impl(std::shared_ptr<Context> ctx, const GlOptions& opt)
    : context(std::move(ctx)), options(opt), pool(opt.workers) {
  if (!context) throw GlError("peelcd::gl::GlImageStage: no context");
  backend = context->backend();
  const int version_loaded = gladLoadGLContextUserPtr(
      &gl,
      [](void* user, const char* name) -> GLADapiproc {
        return reinterpret_cast<GLADapiproc>(static_cast<Context*>(user)->proc_address(name));
      },
      context.get());
  if (version_loaded == 0 || GLAD_VERSION_MAJOR(version_loaded) * 10 + GLAD_VERSION_MINOR(version_loaded) < 45)
    throw GlError("peelcd::gl::GlImageStage: the " + context->backend() +
                  " context does not provide OpenGL 4.5 core");
  timers.bind(gl);
  renderer = reinterpret_cast<const char*>(gl.GetString(GL_RENDERER));
  version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  for (const char* soft : {"llvmpipe", "softpipe", "swrast"})
    if (renderer.find(soft) != std::string::npos) software_renderer = true;
  gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
  GLint64 block = 0;
  gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
  max_storage_block = std::size_t(std::max<GLint64>(block, 0));
  build_programs();
  locate_uniforms();
  create_objects();
  check("Pipeline setup");
}

// Every program, compiled and linked from the embedded sources (shaders/).
void GlImageStage::Impl::build_programs() {
  // Every source through shader_source(): its includes (the batched variants' sit in #ifdefs).
  const auto stage = [&](GLenum type, const char* src, const char* name, const char* defines = "") {
    return compile(type, shader_source(src, defines).c_str(), name);
  };
  peel.id = link({stage(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                       stage(GL_FRAGMENT_SHADER, shaders::peel_frag, "peel.frag")},
                      "peel");
  pcs.id = link({stage(GL_COMPUTE_SHADER, shaders::pcs_comp, "pcs.comp")}, "pcs");
  // The floor (benchmarks): the peel vertex shader and a fragment shader that does nothing.
  floor_draw.id = link({stage(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                        compile(GL_FRAGMENT_SHADER, "#version 450 core\nvoid main() {}\n", "floor.frag")},
                       "floor");
  abuffer.id = link({stage(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                          stage(GL_FRAGMENT_SHADER, shaders::abuffer_frag, "abuffer.frag")},
                         "abuffer");
  resolve.id = link({stage(GL_COMPUTE_SHADER, shaders::abuffer_resolve_comp, "abuffer_resolve.comp")},
                         "abuffer resolve");
  cons.id = link({stage(GL_VERTEX_SHADER, shaders::conservative_vert, "conservative.vert"),
                       stage(GL_GEOMETRY_SHADER, shaders::conservative_geom, "conservative.geom"),
                       stage(GL_FRAGMENT_SHADER, shaders::conservative_frag, "conservative.frag")},
                      "conservative");
  cons_resolve.id =
      link({stage(GL_COMPUTE_SHADER, shaders::conservative_resolve_comp, "conservative_resolve.comp")},
           "conservative resolve");
  // The batched programs: the same sources with PEELCD_BATCH defined.
  const char* batch_define = "#define PEELCD_BATCH\n";
  cons_batch.id = link({stage(GL_VERTEX_SHADER, shaders::conservative_vert, "conservative.vert (PEELCD_BATCH)", batch_define),
                             stage(GL_GEOMETRY_SHADER, shaders::conservative_geom, "conservative.geom (PEELCD_BATCH)", batch_define),
                             stage(GL_FRAGMENT_SHADER, shaders::conservative_frag, "conservative.frag (PEELCD_BATCH)", batch_define)},
                            "conservative batch");
  // Without and with the certified filter: a program each (a uniform switch was not picked up by
  // zink over lavapipe, Mesa 22.3, once a dispatch had run with the other value).
  for (int filter = 0; filter < 2; ++filter) {
    const std::string f = filter ? "#define PEELCD_FILTER_APART\n" : "";
    const std::string deep = "#define PEELCD_DEEP\n" + f;
    cons_batch_resolve[filter].id =
        link({stage(GL_COMPUTE_SHADER, shaders::conservative_batch_resolve_comp, "conservative_batch_resolve.comp", f.c_str())},
             "conservative batch resolve");
    cons_deep[filter].id = link({stage(GL_COMPUTE_SHADER, shaders::conservative_batch_resolve_comp,
                                       "conservative_batch_resolve.comp (PEELCD_DEEP)", deep.c_str())},
                                "conservative batch resolve of deep texels");
    cons_batch_resolve[filter].texels = gl.GetUniformLocation(cons_batch_resolve[filter].id, "texels");
    cons_deep[filter].texels = gl.GetUniformLocation(cons_deep[filter].id, "texels");
    cons_deep[filter].row_base = gl.GetUniformLocation(cons_deep[filter].id, "row_base");
  }
  link_cover_programs();
  point_batch.id = link({stage(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert (PEELCD_BATCH)", batch_define),
                              stage(GL_FRAGMENT_SHADER, shaders::abuffer_frag, "abuffer.frag (PEELCD_BATCH)", batch_define)},
                             "point-sampled batch");
  point_batch_resolve.id = link(
      {stage(GL_COMPUTE_SHADER, shaders::abuffer_resolve_comp, "abuffer_resolve.comp (PEELCD_BATCH)", batch_define)},
      "point-sampled batch resolve");
  select.id =
      link({stage(GL_COMPUTE_SHADER, shaders::batch_select_comp, "batch_select.comp")},
           "batch select");
  prefix_sum.id = link({stage(GL_COMPUTE_SHADER, shaders::prefix_sum_comp, "prefix_sum.comp")}, "prefix sum");
}

// The compute path's coverage (GlOptions::coverage compute), one-view and batched, with the
// share threshold as a define (a constant the compiler folds; the programs are linked again when
// the option changes).
void GlImageStage::Impl::link_cover_programs() {
  const int share_texels = cover_share();
  const std::string share = share_texels < 0 ? std::string() : "#define PEELCD_COVER_SHARE " + std::to_string(share_texels) + "u\n";
  const auto stage = [&](const char* name, const std::string& defines) {
    return compile(GL_COMPUTE_SHADER, shader_source(shaders::conservative_cover_comp, defines.c_str()).c_str(), name);
  };
  for (CoverProgram* c : {&cover, &cover_batch[0], &cover_batch[1]})
    if (c->id != 0) gl.DeleteProgram(c->id), c->id = 0;
  cover.id = link({stage("conservative_cover.comp", share)}, "conservative coverage by compute");
  // Batched: a program for the count pass and one for the fill pass (a uniform switch between
  // two dispatches of one program was not picked up by zink over lavapipe, Mesa 22.3).
  for (int count = 0; count < 2; ++count) {
    const std::string defines = share + "#define PEELCD_BATCH\n#define PEELCD_COUNT_ONLY " + (count ? "true" : "false") + "\n";
    cover_batch[count].id = link({stage(count ? "conservative_cover.comp (PEELCD_BATCH, count pass)"
                                              : "conservative_cover.comp (PEELCD_BATCH, fill pass)",
                                        defines)},
                                 "batched conservative coverage by compute");
    cover_batch[count].row = gl.GetUniformLocation(cover_batch[count].id, "row");
  }
  cover_share_linked = share_texels;
}

// Every program's uniform locations, by the names in its sources.
void GlImageStage::Impl::locate_uniforms() {
  peel.clip = gl.GetUniformLocation(peel.id, "clip_from_local");
  peel.box_lo = gl.GetUniformLocation(peel.id, "box_lo");
  peel.box_hi = gl.GetUniformLocation(peel.id, "box_hi");
  peel.has_prev = gl.GetUniformLocation(peel.id, "has_previous");
  peel.rank_flip = gl.GetUniformLocation(peel.id, "rank_flip");
  peel.object = gl.GetUniformLocation(peel.id, "object_bit");
  peel.model = gl.GetUniformLocation(peel.id, "roi_from_object");
  pcs.eps = gl.GetUniformLocation(pcs.id, "epsilon_window");
  pcs.slope = gl.GetUniformLocation(pcs.id, "slope");
  pcs.res = gl.GetUniformLocation(pcs.id, "resolution");
  pcs.track = gl.GetUniformLocation(pcs.id, "track_runs");
  floor_draw.clip = gl.GetUniformLocation(floor_draw.id, "clip_from_local");
  floor_draw.model = gl.GetUniformLocation(floor_draw.id, "roi_from_object");
  floor_draw.lo = gl.GetUniformLocation(floor_draw.id, "box_lo");
  floor_draw.hi = gl.GetUniformLocation(floor_draw.id, "box_hi");
  abuffer.clip = gl.GetUniformLocation(abuffer.id, "clip_from_local");
  abuffer.lo = gl.GetUniformLocation(abuffer.id, "box_lo");
  abuffer.hi = gl.GetUniformLocation(abuffer.id, "box_hi");
  abuffer.object = gl.GetUniformLocation(abuffer.id, "object_bit");
  abuffer.model = gl.GetUniformLocation(abuffer.id, "roi_from_object");
  abuffer.res = gl.GetUniformLocation(abuffer.id, "resolution");
  abuffer.slots = gl.GetUniformLocation(abuffer.id, "slots");
  resolve.slots = gl.GetUniformLocation(resolve.id, "slots");
  resolve.eps = gl.GetUniformLocation(resolve.id, "epsilon_window");
  resolve.slope = gl.GetUniformLocation(resolve.id, "slope");
  resolve.res = gl.GetUniformLocation(resolve.id, "resolution");
  resolve.full = gl.GetUniformLocation(resolve.id, "full_peel");
  resolve.first = gl.GetUniformLocation(resolve.id, "first_object");
  resolve.append = gl.GetUniformLocation(resolve.id, "append_pcs");
  resolve.emit = gl.GetUniformLocation(resolve.id, "emit_layer");
  cons.clip = gl.GetUniformLocation(cons.id, "clip_from_local");
  cons.model = gl.GetUniformLocation(cons.id, "roi_from_object");
  cons.res = gl.GetUniformLocation(cons.id, "resolution");
  cons.slots = gl.GetUniformLocation(cons.id, "slots");
  cons.object = gl.GetUniformLocation(cons.id, "object_bit");
  cons.grow_texels = gl.GetUniformLocation(cons.id, "grow_texels");
  cons.grow_depth = gl.GetUniformLocation(cons.id, "grow_depth");
  cons_resolve.res = gl.GetUniformLocation(cons_resolve.id, "resolution");
  cons_resolve.slots = gl.GetUniformLocation(cons_resolve.id, "slots");
  cons_resolve.append = gl.GetUniformLocation(cons_resolve.id, "append_pcs");
  cons_resolve.emit = gl.GetUniformLocation(cons_resolve.id, "emit_layer");
  cons_batch.count_only = gl.GetUniformLocation(cons_batch.id, "count_only");
  cons_batch.viewport = gl.GetUniformLocation(cons_batch.id, "viewport");
  point_batch.viewport = gl.GetUniformLocation(point_batch.id, "viewport");
  point_batch.count_only = gl.GetUniformLocation(point_batch.id, "count_only");
  point_batch_resolve.texels = gl.GetUniformLocation(point_batch_resolve.id, "texels");
  select.jobs = gl.GetUniformLocation(select.id, "job_count");
  select.invocations = gl.GetUniformLocation(select.id, "invocations");
  select.conservative = gl.GetUniformLocation(select.id, "conservative");
  select.row = gl.GetUniformLocation(select.id, "row");
  select.pass = gl.GetUniformLocation(select.id, "pass");
  prefix_sum.texels = gl.GetUniformLocation(prefix_sum.id, "texels");
  prefix_sum.blocks = gl.GetUniformLocation(prefix_sum.id, "block_count");
  prefix_sum.pass = gl.GetUniformLocation(prefix_sum.id, "pass");
}

// The vertex arrays, buffers, textures and query the peelers and the batch reuse (grown later).
void GlImageStage::Impl::create_objects() {
  gl.CreateBuffers(1, &count_buffer);
  gl.CreateBuffers(1, &fragment_buffer);
  gl.CreateTextures(GL_TEXTURE_BUFFER, 1, &count_tex);
  gl.CreateTextures(GL_TEXTURE_BUFFER, 1, &fragment_tex);
  gl.CreateTextures(GL_TEXTURE_BUFFER, 2, corner_tex);
  gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texture_buffer);
  gl.CreateVertexArrays(1, &vao);
  gl.EnableVertexArrayAttrib(vao, 0);
  gl.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  gl.VertexArrayAttribBinding(vao, 0, 0);
  gl.EnableVertexArrayAttrib(vao, 1);
  gl.VertexArrayAttribIFormat(vao, 1, 1, GL_UNSIGNED_INT, offsetof(GpuVertex, id));
  gl.VertexArrayAttribBinding(vao, 1, 0);
  gl.CreateBuffers(2, vbo);
  gl.CreateBuffers(2, ibo);
  gl.CreateBuffers(1, &batch.frame);
  gl.CreateBuffers(1, &batch.positions);
  gl.CreateBuffers(1, &batch.views);
  gl.CreateBuffers(1, &batch.entries);
  gl.CreateBuffers(1, &batch.jobs);
  gl.CreateBuffers(1, &batch.command);
  gl.NamedBufferData(batch.command, 16, nullptr, GL_DYNAMIC_DRAW);
  gl.CreateBuffers(1, &resident_buffer);
  gl.NamedBufferData(resident_buffer, 16, nullptr, GL_STATIC_DRAW);
  gl.CreateVertexArrays(1, &batch.vao);
  gl.CreateBuffers(1, &batch.layers);
  gl.CreateBuffers(1, &batch.deep_rows);
  gl.CreateBuffers(1, &batch.offset_buffer);
  gl.CreateBuffers(1, &batch.scan_blocks);
  gl.CreateBuffers(1, &batch.scan_total);
  gl.CreateBuffers(1, &batch.staged);
  gl.CreateBuffers(1, &batch.regions);
  gl.CreateBuffers(1, &batch.grid);
  gl.CreateBuffers(1, &cover_params);
  gl.NamedBufferData(cover_params, 512, nullptr, GL_DYNAMIC_DRAW);
  gl.NamedBufferData(batch.scan_total, 4, nullptr, GL_DYNAMIC_READ);
  gl.CreateQueries(GL_ANY_SAMPLES_PASSED, 1, &query);
  gl.CreateBuffers(1, &pcs_buffer);
  grow_pcs(1 << 16);
}

GlImageStage::Impl::~Impl() {
  // The caller may have another context current: make ours current, then give theirs back.
  try {
    context->make_current();
  } catch (const GlError&) {
    return;  // the context is gone: its objects went with it
  }
  timers.release();
  gl.DeleteProgram(peel.id);
  gl.DeleteProgram(pcs.id);
  gl.DeleteProgram(floor_draw.id);
  gl.DeleteProgram(abuffer.id);
  gl.DeleteProgram(resolve.id);
  gl.DeleteProgram(cons.id);
  gl.DeleteProgram(cons_resolve.id);
  gl.DeleteProgram(cons_batch.id);
  gl.DeleteProgram(cover.id);
  gl.DeleteProgram(cover_batch[0].id);
  gl.DeleteProgram(cover_batch[1].id);
  for (int filter = 0; filter < 2; ++filter) {
    gl.DeleteProgram(cons_batch_resolve[filter].id);
    gl.DeleteProgram(cons_deep[filter].id);
  }
  gl.DeleteProgram(select.id);
  gl.DeleteProgram(point_batch.id);
  gl.DeleteProgram(point_batch_resolve.id);
  gl.DeleteProgram(prefix_sum.id);
  gl.DeleteBuffers(1, &batch.frame);
  gl.DeleteBuffers(1, &batch.positions);
  gl.DeleteBuffers(1, &batch.views);
  gl.DeleteBuffers(1, &batch.entries);
  gl.DeleteBuffers(1, &batch.jobs);
  gl.DeleteBuffers(1, &batch.command);
  gl.DeleteBuffers(1, &resident_buffer);
  gl.DeleteVertexArrays(1, &batch.vao);
  gl.DeleteBuffers(1, &batch.layers);
  gl.DeleteBuffers(1, &batch.deep_rows);
  gl.DeleteBuffers(1, &batch.offset_buffer);
  gl.DeleteBuffers(1, &batch.scan_blocks);
  gl.DeleteBuffers(1, &batch.scan_total);
  gl.DeleteBuffers(1, &batch.staged);
  gl.DeleteBuffers(1, &batch.regions);
  gl.DeleteBuffers(1, &batch.grid);
  gl.DeleteBuffers(1, &cover_params);
  gl.DeleteBuffers(1, &count_buffer);
  gl.DeleteBuffers(1, &fragment_buffer);
  gl.DeleteTextures(1, &count_tex);
  gl.DeleteTextures(1, &fragment_tex);
  gl.DeleteTextures(2, corner_tex);
  gl.DeleteVertexArrays(1, &vao);
  gl.DeleteBuffers(2, vbo);
  gl.DeleteBuffers(2, ibo);
  for (auto& [key, shape] : shapes) gl.DeleteBuffers(1, &shape.vbo);
  gl.DeleteQueries(1, &query);
  gl.DeleteBuffers(1, &pcs_buffer);
  release_layers();
  if (bare_fbo) gl.DeleteFramebuffers(1, &bare_fbo);
  context->restore_previous();
}

void GlImageStage::Impl::check(const char* where) {
  GLenum err = gl.GetError();
  if (err == GL_NO_ERROR) return;
  std::ostringstream msg;
  msg << "peelcd::gl::GlImageStage: GL error 0x" << std::hex << err << " after " << where;
  while ((err = gl.GetError()) != GL_NO_ERROR) msg << ", 0x" << err;
  throw GlError(msg.str());
}

std::string shader_source(const char* src, const std::string& defines) {
  std::string out = src;
  // `defines` right after the #version line (the first line of every source).
  const std::size_t eol = out.find('\n');
  out.insert(eol == std::string::npos ? out.size() : eol + 1, defines);
  // The shared sources where a source asks for them (GLSL has no #include of its own): the PCS
  // tests (shared with C++) and the batched views' records (shaders/batch.inc).
  const std::pair<std::string, std::string> includes[] = {
      {"#include \"peelcd/core/image/pcs_test.inc\"",
       std::string("#define PEELCD_PCS_FN\n#define PEELCD_ABS abs\n") + shaders::pcs_test_inc},
      {"#include \"peelcd/core/image/certified_apart.inc\"", std::string("#define PEELCD_PCS_FN\n") + shaders::certified_apart_inc},
      {"#include \"batch.inc\"", shaders::batch_inc},
      {"#include \"conservative.inc\"", shaders::conservative_inc}};
  for (const auto& [line, text] : includes)
    if (const std::size_t at = out.find(line); at != std::string::npos) out.replace(at, line.size(), text);
  return out;
}

GLuint GlImageStage::Impl::compile(GLenum type, const char* src, const char* name) {
  GLuint s = gl.CreateShader(type);
  gl.ShaderSource(s, 1, &src, nullptr);
  gl.CompileShader(s);
  GLint ok = 0;
  gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
    gl.DeleteShader(s);
    throw GlError(std::string("peelcd::gl::GlImageStage: cannot compile shaders/") + name + ": " + log);
  }
  return s;
}

GLuint GlImageStage::Impl::link(std::initializer_list<GLuint> stages, const char* name) {
  GLuint p = gl.CreateProgram();
  for (GLuint s : stages) gl.AttachShader(p, s);
  gl.LinkProgram(p);
  for (GLuint s : stages) gl.DeleteShader(s);
  GLint ok = 0;
  gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    gl.GetProgramInfoLog(p, sizeof log, nullptr, log);
    gl.DeleteProgram(p);
    throw GlError(std::string("peelcd::gl::GlImageStage: cannot link the ") + name + " program: " + log);
  }
  return p;
}

}  // namespace peelcd::gl
