#include "gl/pipeline.h"

#include "core/broad_phase.h"
#include "core/cull.h"
#include "core/kbuffer.h"
#include "core/view.h"

#include <glad/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

namespace peelcd::shaders {
extern const char* const peel_vert;
extern const char* const peel_frag;
extern const char* const pcs_comp;
extern const char* const abuffer_frag;
extern const char* const abuffer_resolve_comp;
extern const char* const shader_sources_hash;
}  // namespace peelcd::shaders

namespace peelcd::gl {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// One corner of an uploaded triangle: ROI-local position and the corner's ID.
struct GpuVertex {
  float x, y, z;
  std::uint32_t id;
};
static_assert(sizeof(GpuVertex) == 16, "vertex layout is 16 bytes");

// Header of the PCS append buffer; matches PcsBuffer in shaders/pcs.comp and
// shaders/abuffer_resolve.comp (the multi-pass peeler leaves the last two words alone).
struct PcsHeader {
  std::uint32_t count, capacity, max_layers, max_fragments;
};

// Peel passes per ROI before giving up; each pass strictly increases every live texel's depth,
// so only a scene with more than this many surfaces along one ray reaches it.
constexpr int kMaxPasses = 4096;

}  // namespace

struct Pipeline::Impl {
  Context& context;
  GladGLContext gl{};
  GLuint peel_program = 0, pcs_program = 0;
  GLint u_clip = -1, u_box_lo = -1, u_box_hi = -1, u_has_prev = -1, u_object = -1;
  GLint u_eps = -1, u_slope = -1, u_res = -1, u_track = -1;
  GLuint vao = 0, vbo[2] = {0, 0};
  std::size_t vbo_capacity[2] = {0, 0};  // in vertices
  GLuint layer_tex[2] = {0, 0}, run_tex = 0, depth_rb = 0, fbo[2] = {0, 0}, bare_fbo = 0;
  int layer_size = 0, bare_size = 0;
  GLuint query = 0, pcs_buffer = 0;
  std::uint32_t pcs_capacity = 0;
  std::size_t passes_this_frame = 0, pcs_readbacks = 0;
  GLuint floor_program = 0, abuffer_program = 0, resolve_program = 0;
  GLint u_ab_clip = -1, u_ab_lo = -1, u_ab_hi = -1, u_ab_object = -1;
  GLint u_ab_res = -1, u_ab_slots = -1;
  GLint u_rs_eps = -1, u_rs_slope = -1, u_rs_res = -1, u_rs_full = -1, u_rs_first = -1, u_rs_append = -1,
        u_rs_emit = -1, u_rs_slots = -1;
  // The k-buffer of the single-pass peeler (shaders/abuffer.frag): per-texel fragment counts
  // and up to `slots` fragments of 16 bytes per texel; the resolve reads both, and the corners
  // the objects were drawn from, through buffer textures. Sized for `kbuffer_texels` texels and
  // `kbuffer_fragments` fragments.
  GLuint count_buffer = 0, fragment_buffer = 0, count_tex = 0, fragment_tex = 0, corner_tex[2] = {0, 0};
  GLint max_texture_buffer = 0;  // GL_MAX_TEXTURE_BUFFER_SIZE, texels
  std::uint32_t slots = 16;
  std::size_t kbuffer_texels = 0, kbuffer_fragments = 0;
  GLint u_floor_clip = -1, u_floor_lo = -1, u_floor_hi = -1;
  std::string renderer, version;
  GLint max_texture = 0;
  std::size_t max_storage_block = 0;  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE, bytes

  // Scratch reused across ROIs and frames (no allocation in steady state).
  std::vector<GpuVertex> staging[2];
  // Per slot of the ROI being peeled: a world-space object's corners in `staging`, or a rigid
  // object's cached shape with the corner indices of its triangles in the ROI.
  struct CachedShape {
    std::weak_ptr<const Mesh> owner;
    GLuint vbo = 0;
    std::size_t corners = 0;  // in the VBO: 3 per triangle of the shape
    // Each triangle's provoking-corner ID (the host resolve's; an indexed draw's order is the
    // shape's triangle index, gl_VertexID / 3 of its corners 3t + k).
    std::vector<std::uint32_t> provoking_ids;
  };
  std::map<std::pair<const Mesh*, IdMode>, CachedShape> shapes;
  std::vector<std::uint32_t> indices[2];
  const CachedShape* slot_shape[2] = {nullptr, nullptr};
  std::array<float, 16> slot_model[2];
  GLuint ibo[2] = {0, 0};
  std::size_t ibo_capacity[2] = {0, 0};
  std::size_t shape_uploads = 0;
  GLint u_model_peel = -1, u_model_ab = -1, u_model_floor = -1;
  std::vector<IdPair> pcs, pcs_all;
  std::vector<std::uint64_t> candidates, candidate_scratch, pcs_keys;
  ContactCull cull;
  // The host resolve (Resolve::host): triangle ID by draw order per slot, and the threads.
  std::vector<std::uint32_t> ids_by_order[2];
  WorkerPool pool;  // the host resolve's threads
  KResolver resolver{pool};
  bool software_renderer = false;  // GL runs on the CPU: Resolve::automatic resolves on the host
  std::vector<Aabb> boxes;
  std::vector<std::pair<std::size_t, std::size_t>> object_pairs;
  std::vector<std::size_t> order;
  IdMap map_a, map_b;
  std::vector<CapturedView>* capture = nullptr;
  CapturedView* captured = nullptr;  // the view being peeled, while capturing

  explicit Impl(Context& ctx) : context(ctx) {
    context.make_current();
    const int version_loaded = gladLoadGLContextUserPtr(
        &gl,
        [](void* user, const char* name) -> GLADapiproc {
          return reinterpret_cast<GLADapiproc>(static_cast<Context*>(user)->proc_address(name));
        },
        &context);
    if (version_loaded == 0 || GLAD_VERSION_MAJOR(version_loaded) * 10 + GLAD_VERSION_MINOR(version_loaded) < 45)
      throw GlError("peelcd::gl::Pipeline: the " + context.backend() +
                    " context does not provide OpenGL 4.5 core");
    renderer = reinterpret_cast<const char*>(gl.GetString(GL_RENDERER));
    version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
    for (const char* soft : {"llvmpipe", "softpipe", "swrast"})
      if (renderer.find(soft) != std::string::npos) software_renderer = true;
    gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
    GLint64 block = 0;
    gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
    max_storage_block = std::size_t(std::max<GLint64>(block, 0));

    peel_program = link({compile(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                         compile(GL_FRAGMENT_SHADER, shaders::peel_frag, "peel.frag")},
                        "peel");
    pcs_program = link({compile(GL_COMPUTE_SHADER, shaders::pcs_comp, "pcs.comp")}, "pcs");
    // The floor (benchmarks): the peel vertex shader and a fragment shader that does nothing.
    floor_program = link({compile(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                          compile(GL_FRAGMENT_SHADER, "#version 450 core\nvoid main() {}\n", "floor.frag")},
                         "floor");
    abuffer_program = link({compile(GL_VERTEX_SHADER, shaders::peel_vert, "peel.vert"),
                            compile(GL_FRAGMENT_SHADER, shaders::abuffer_frag, "abuffer.frag")},
                           "abuffer");
    resolve_program = link({compile(GL_COMPUTE_SHADER, shaders::abuffer_resolve_comp, "abuffer_resolve.comp")},
                           "abuffer resolve");
    u_ab_clip = gl.GetUniformLocation(abuffer_program, "clip_from_local");
    u_ab_lo = gl.GetUniformLocation(abuffer_program, "box_lo");
    u_ab_hi = gl.GetUniformLocation(abuffer_program, "box_hi");
    u_ab_object = gl.GetUniformLocation(abuffer_program, "object_bit");
    u_model_ab = gl.GetUniformLocation(abuffer_program, "roi_from_object");
    u_ab_res = gl.GetUniformLocation(abuffer_program, "resolution");
    u_ab_slots = gl.GetUniformLocation(abuffer_program, "slots");
    u_rs_slots = gl.GetUniformLocation(resolve_program, "slots");
    u_rs_eps = gl.GetUniformLocation(resolve_program, "epsilon_window");
    u_rs_slope = gl.GetUniformLocation(resolve_program, "slope");
    u_rs_res = gl.GetUniformLocation(resolve_program, "resolution");
    u_rs_full = gl.GetUniformLocation(resolve_program, "full_peel");
    u_rs_first = gl.GetUniformLocation(resolve_program, "first_object");
    u_rs_append = gl.GetUniformLocation(resolve_program, "append_pcs");
    u_rs_emit = gl.GetUniformLocation(resolve_program, "emit_layer");
    gl.CreateBuffers(1, &count_buffer);
    gl.CreateBuffers(1, &fragment_buffer);
    gl.CreateTextures(GL_TEXTURE_BUFFER, 1, &count_tex);
    gl.CreateTextures(GL_TEXTURE_BUFFER, 1, &fragment_tex);
    gl.CreateTextures(GL_TEXTURE_BUFFER, 2, corner_tex);
    gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texture_buffer);
    u_floor_clip = gl.GetUniformLocation(floor_program, "clip_from_local");
    u_model_floor = gl.GetUniformLocation(floor_program, "roi_from_object");
    u_floor_lo = gl.GetUniformLocation(floor_program, "box_lo");
    u_floor_hi = gl.GetUniformLocation(floor_program, "box_hi");
    u_clip = gl.GetUniformLocation(peel_program, "clip_from_local");
    u_box_lo = gl.GetUniformLocation(peel_program, "box_lo");
    u_box_hi = gl.GetUniformLocation(peel_program, "box_hi");
    u_has_prev = gl.GetUniformLocation(peel_program, "has_previous");
    u_eps = gl.GetUniformLocation(pcs_program, "epsilon_window");
    u_object = gl.GetUniformLocation(peel_program, "object_bit");
    u_slope = gl.GetUniformLocation(pcs_program, "slope");
    u_res = gl.GetUniformLocation(pcs_program, "resolution");
    u_track = gl.GetUniformLocation(pcs_program, "track_runs");

    gl.CreateVertexArrays(1, &vao);
    gl.EnableVertexArrayAttrib(vao, 0);
    gl.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
    gl.VertexArrayAttribBinding(vao, 0, 0);
    gl.EnableVertexArrayAttrib(vao, 1);
    gl.VertexArrayAttribIFormat(vao, 1, 1, GL_UNSIGNED_INT, offsetof(GpuVertex, id));
    gl.VertexArrayAttribBinding(vao, 1, 0);
    gl.CreateBuffers(2, vbo);
    gl.CreateBuffers(2, ibo);
    u_model_peel = gl.GetUniformLocation(peel_program, "roi_from_object");
    gl.CreateQueries(GL_ANY_SAMPLES_PASSED, 1, &query);
    gl.CreateBuffers(1, &pcs_buffer);
    grow_pcs(1 << 16);
    check("Pipeline setup");
  }

  ~Impl() {
    context.make_current();
    gl.DeleteProgram(peel_program);
    gl.DeleteProgram(pcs_program);
    gl.DeleteProgram(floor_program);
    gl.DeleteProgram(abuffer_program);
    gl.DeleteProgram(resolve_program);
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
  }

  void check(const char* where) {
    GLenum err = gl.GetError();
    if (err == GL_NO_ERROR) return;
    std::ostringstream msg;
    msg << "peelcd::gl::Pipeline: GL error 0x" << std::hex << err << " after " << where;
    while ((err = gl.GetError()) != GL_NO_ERROR) msg << ", 0x" << err;
    throw GlError(msg.str());
  }

  GLuint compile(GLenum type, const char* src, const char* name) {
    GLuint s = gl.CreateShader(type);
    gl.ShaderSource(s, 1, &src, nullptr);
    gl.CompileShader(s);
    GLint ok = 0;
    gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[4096] = {0};
      gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
      gl.DeleteShader(s);
      throw GlError(std::string("peelcd::gl::Pipeline: cannot compile shaders/") + name + ": " + log);
    }
    return s;
  }

  GLuint link(std::initializer_list<GLuint> stages, const char* name) {
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
      throw GlError(std::string("peelcd::gl::Pipeline: cannot link the ") + name + " program: " + log);
    }
    return p;
  }

  void grow_pcs(std::uint32_t capacity) {
    pcs_capacity = capacity;
    gl.NamedBufferData(pcs_buffer, sizeof(PcsHeader) + std::size_t(capacity) * 8, nullptr, GL_DYNAMIC_READ);
  }

  // The most fragments per texel a k-buffer of `texels` texels can hold: 16 bytes each, within
  // the largest shader storage block and the largest buffer texture (whose texel index is a
  // 32-bit signed integer in the shaders).
  std::size_t fitting_slots(std::size_t texels) const {
    return std::min(max_storage_block / 16, fetchable()) / std::max<std::size_t>(texels, 1);
  }

  // Texels a shader can fetch from a buffer texture: GL_MAX_TEXTURE_BUFFER_SIZE, and the
  // shaders' index is a 32-bit signed integer.
  std::size_t fetchable() const {
    return std::min<std::size_t>(std::size_t(std::max(max_texture_buffer, 0)), 0x7fffffff);
  }

  // The k-buffer for `texels` texels with `view_slots` fragments each: 4 bytes of count per
  // texel, 16 bytes per fragment. Grows only (steady state allocates nothing), and always to
  // the largest tile seen so far with the most slots asked for (within the largest storage
  // block): the tile changes with the number of ROIs from frame to frame, and a small deep tile
  // followed by a large one would otherwise grow it twice.
  void ensure_kbuffer(std::size_t texels, std::size_t view_slots) {
    if (texels > kbuffer_texels) {
      gl.NamedBufferData(count_buffer, GLsizeiptr(texels * 4), nullptr, GL_DYNAMIC_COPY);
      kbuffer_texels = texels;
      gl.TextureBuffer(count_tex, GL_R32UI, count_buffer);
    }
    const std::size_t most = std::min(max_storage_block / 16, fetchable());
    const std::size_t wanted = std::max(texels * view_slots, std::min(kbuffer_texels * view_slots, most));
    if (wanted > kbuffer_fragments) {
      kbuffer_fragments = wanted;
      gl.NamedBufferData(fragment_buffer, GLsizeiptr(kbuffer_fragments * 16), nullptr, GL_DYNAMIC_COPY);
      gl.TextureBuffer(fragment_tex, GL_RGBA32UI, fragment_buffer);
    }
  }

  void release_layers() {
    if (!layer_size) return;
    gl.DeleteFramebuffers(2, fbo);
    gl.DeleteTextures(2, layer_tex);
    gl.DeleteTextures(1, &run_tex);
    gl.DeleteRenderbuffers(1, &depth_rb);
    layer_size = 0;
  }

  // Two ping-pong layer textures (RGBA32UI, see shaders/peel.frag) sharing one depth buffer,
  // and the run-start texture of full peeling (shaders/pcs.comp).
  void ensure_layers(int n) {
    if (n == layer_size) return;
    release_layers();
    gl.CreateTextures(GL_TEXTURE_2D, 2, layer_tex);
    gl.CreateTextures(GL_TEXTURE_2D, 1, &run_tex);
    gl.TextureStorage2D(run_tex, 1, GL_RGBA32UI, n, n);
    gl.CreateRenderbuffers(1, &depth_rb);
    gl.NamedRenderbufferStorage(depth_rb, GL_DEPTH_COMPONENT32F, n, n);
    gl.CreateFramebuffers(2, fbo);
    for (int i = 0; i < 2; ++i) {
      gl.TextureStorage2D(layer_tex[i], 1, GL_RGBA32UI, n, n);
      gl.TextureParameteri(layer_tex[i], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      gl.TextureParameteri(layer_tex[i], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      gl.NamedFramebufferTexture(fbo[i], GL_COLOR_ATTACHMENT0, layer_tex[i], 0);
      gl.NamedFramebufferRenderbuffer(fbo[i], GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
      if (gl.CheckNamedFramebufferStatus(fbo[i], GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw GlError("peelcd::gl::Pipeline: layer framebuffer of " + std::to_string(n) + "^2 is incomplete");
    }
    layer_size = n;
    check("layer allocation");
  }

  // The k-buffer draw writes storage buffers only: a framebuffer without attachments (no
  // colour or depth tiles for a software rasterizer to load and store). Only its size follows
  // the tile (which changes with the number of ROIs and their triangles' size); the layer
  // textures, which the k-buffer does not need, are not reallocated for it.
  void ensure_bare_fbo(int n) {
    if (bare_fbo == 0) gl.CreateFramebuffers(1, &bare_fbo);
    if (n == bare_size) return;
    gl.NamedFramebufferParameteri(bare_fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, n);
    gl.NamedFramebufferParameteri(bare_fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, n);
    if (gl.CheckNamedFramebufferStatus(bare_fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("peelcd::gl::Pipeline: attachment-less framebuffer of " + std::to_string(n) + "^2 is incomplete");
    bare_size = n;
    check("framebuffer resize");
  }

  // Calls emit(t, k, local) for every corner k of every triangle t of `mesh` whose box touches
  // the ROI box, local = corner - ROI centre (double). Returns the smallest depth along d of
  // those corners, clamped to the ROI.
  // With `only`, just the triangles it lists (ascending) are candidates.
  template <class Emit>
  static double for_each_corner_in_roi(const Mesh& mesh, const RoiView& view, const std::vector<std::uint32_t>* only,
                                       Emit&& emit) {
    double min_depth = view.half_depth;
    const Aabb& box = view.box;
    const std::size_t count = only ? only->size() : mesh.triangles.size();
    for (std::size_t i = 0; i < count; ++i) {
      const auto t = only ? (*only)[i] : std::uint32_t(i);
      const Tri& f = mesh.triangles[t];
      const Vec3& a = mesh.vertices[f[0]];
      const Vec3& b = mesh.vertices[f[1]];
      const Vec3& c = mesh.vertices[f[2]];
      const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
      if ((hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any()) continue;
      for (int k = 0; k < 3; ++k) {
        const Vec3 local = mesh.vertices[f[k]] - view.center;
        emit(t, k, local);
        min_depth = std::min(min_depth, std::max(-view.half_depth, local.dot(view.frame.d)));
      }
    }
    return min_depth;
  }

  // Gathers the triangles of `mesh` touching the ROI box into `out` (ROI-local floats).
  double gather(const Mesh& mesh, const RoiView& view, const std::vector<std::uint32_t>* only, IdMode ids,
                std::vector<GpuVertex>& out) {
    out.clear();
    return for_each_corner_in_roi(mesh, view, only, [&](std::uint32_t t, int k, const Vec3& local) {
      out.push_back({float(local.x()), float(local.y()), float(local.z()), corner_id(mesh, t, k, ids)});
    });
  }

  // Corners in the VBO a slot draws from (its triangles in the ROI, or a rigid shape's all).
  std::size_t vbo_corners(int slot) const { return slot_shape[slot] ? slot_shape[slot]->corners : staging[slot].size(); }
  // Number of corners slot `slot` draws for the current ROI view.
  std::size_t corners(int slot) const { return slot_shape[slot] ? indices[slot].size() : staging[slot].size(); }

  // Prepares slot `slot` for `object` in `view`: a world-space object's triangles touching the
  // ROI gathered into `staging`, or a rigid object's triangle indices (its shape cached on the
  // GPU). Returns the smallest depth along d of the gathered corners, clamped to the ROI.
  // With `only`, just the triangles it lists (contact-region culling) are candidates.
  double prepare(const Object& object, const RoiView& view, const std::vector<std::uint32_t>* only, IdMode ids,
                 int slot) {
    if (!object.rigid || !object.rigid->shape) {
      slot_shape[slot] = nullptr;
      return gather(object.mesh, view, only, ids, staging[slot]);
    }
    // World space: culling and depth as for any object; only the corner indices go up.
    std::vector<std::uint32_t>& out = indices[slot];
    out.clear();
    const double min_depth = for_each_corner_in_roi(
        object.mesh, view, only, [&](std::uint32_t t, int k, const Vec3&) { out.push_back(3 * t + std::uint32_t(k)); });
    slot_shape[slot] = &cached_shape(object.rigid->shape, ids);
    // ROI-local from shape-local, composed in double, rounded once.
    Eigen::Affine3d m = object.rigid->pose;
    m.translation() -= view.center;
    const Eigen::Matrix4d mm = m.matrix();
    for (int i = 0; i < 16; ++i) slot_model[slot][i] = float(mm(i % 4, i / 4));
    return min_depth;
  }

  // The GPU copy of a rigid shape (every triangle's corners in shape-local floats, with IDs),
  // uploaded the first time it is seen with this ID mode. Shapes no longer held are dropped.
  const CachedShape& cached_shape(const std::shared_ptr<const Mesh>& shape, IdMode ids) {
    auto it = shapes.find({shape.get(), ids});
    if (it != shapes.end() && !it->second.owner.expired()) return it->second;
    if (it != shapes.end()) {
      gl.DeleteBuffers(1, &it->second.vbo);
      shapes.erase(it);
    }
    std::vector<GpuVertex> corners_local;
    corners_local.reserve(shape->triangles.size() * 3);
    for (std::uint32_t t = 0; t < shape->triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = shape->vertices[shape->triangles[t][k]];
        corners_local.push_back({float(p.x()), float(p.y()), float(p.z()), corner_id(*shape, t, k, ids)});
      }
    CachedShape c;
    c.owner = shape;
    c.corners = corners_local.size();
    c.provoking_ids.reserve(c.corners / 3);
    for (std::size_t i = 2; i < corners_local.size(); i += 3) c.provoking_ids.push_back(corners_local[i].id);
    gl.CreateBuffers(1, &c.vbo);
    gl.NamedBufferData(c.vbo, GLsizeiptr(corners_local.size() * sizeof(GpuVertex)), corners_local.data(), GL_STATIC_DRAW);
    ++shape_uploads;
    return shapes.emplace(std::make_pair(shape.get(), ids), std::move(c)).first->second;
  }

  void drop_expired_shapes() {
    for (auto it = shapes.begin(); it != shapes.end();) {
      if (it->second.owner.expired()) {
        gl.DeleteBuffers(1, &it->second.vbo);
        it = shapes.erase(it);
      } else {
        ++it;
      }
    }
  }

  // Contact-region culling of one object pair into `cull` (kept triangles, shrunk box) and the
  // tile that box gets (`share`, or less by edge_tile_resolution() when sharing the budget):
  // what detect() peels and floor_ms() times. 0 when nothing is kept (no contact possible).
  int cull_pair(const Mesh& a, const Mesh& b, const Aabb& roi, const DetectOptions& opt, int share) {
    cull_to_contact_region(a, b, roi, cull);
    if (cull.box.empty()) return 0;
    if (opt.resolution > 0) return share;
    return edge_tile_resolution(share, cull.box, cull.median_edge, opt.edge_texels);
  }

  // Draws slot `slot` with the current program, whose roi_from_object is at `u_model`.
  void draw(int slot, GLint u_model) {
    static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    if (!slot_shape[slot]) {
      gl.UniformMatrix4fv(u_model, 1, GL_FALSE, identity);
      gl.VertexArrayVertexBuffer(vao, 0, vbo[slot], 0, sizeof(GpuVertex));
      gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(staging[slot].size()));
      return;
    }
    gl.UniformMatrix4fv(u_model, 1, GL_FALSE, slot_model[slot].data());
    gl.VertexArrayVertexBuffer(vao, 0, slot_shape[slot]->vbo, 0, sizeof(GpuVertex));
    gl.VertexArrayElementBuffer(vao, ibo[slot]);
    gl.DrawElements(GL_TRIANGLES, GLsizei(indices[slot].size()), GL_UNSIGNED_INT, nullptr);
  }

  void upload(int slot) {
    if (slot_shape[slot]) {  // a rigid shape: only the indices
      const std::size_t n = indices[slot].size();
      if (n > ibo_capacity[slot]) {
        ibo_capacity[slot] = std::max<std::size_t>(n, ibo_capacity[slot] * 3 / 2);
        gl.NamedBufferData(ibo[slot], ibo_capacity[slot] * sizeof(std::uint32_t), nullptr, GL_STREAM_DRAW);
      }
      gl.NamedBufferSubData(ibo[slot], 0, n * sizeof(std::uint32_t), indices[slot].data());
      return;
    }
    const std::size_t n = staging[slot].size();
    if (n > vbo_capacity[slot]) {
      vbo_capacity[slot] = std::max<std::size_t>(n, vbo_capacity[slot] * 3 / 2);
      gl.NamedBufferData(vbo[slot], vbo_capacity[slot] * sizeof(GpuVertex), nullptr, GL_STREAM_DRAW);
    }
    gl.NamedBufferSubData(vbo[slot], 0, n * sizeof(GpuVertex), staging[slot].data());
  }

  // Single-pass peeling (Peeler::abuffer): both objects drawn once into a per-texel k-buffer,
  // then one compute pass recovers the layers and appends the PCS. Same contract as peel();
  // returns false if a texel had more fragments than slots or the PCS buffer overflowed (grown;
  // the caller peels again). A view whose k-buffer would exceed the largest shader storage
  // block is peeled by multi-pass instead (the same layers and PCS).
  bool peel_single_pass(const RoiView& view, double epsilon_world, const DetectOptions& opt, int first_slot,
                        PairResult& r, Timings& t) {
    const int n = view.resolution;
    const std::size_t texels = std::size_t(n) * std::size_t(n);
    // The resolve fetches the corners through buffer textures too.
    const std::size_t fitting = fitting_slots(texels);
    const auto view_slots = std::uint32_t(std::min<std::size_t>(slots, fitting));
    if (view_slots == 0 || std::max(vbo_corners(0), vbo_corners(1)) > fetchable())
      return peel(view, epsilon_world, opt, first_slot, r, t);
    const auto t_gpu = Clock::now();
    ensure_bare_fbo(n);
    ensure_kbuffer(texels, view_slots);
    const GLuint zero = 0;
    gl.ClearNamedBufferSubData(count_buffer, GL_R32UI, 0, GLsizeiptr(texels * 4), GL_RED_INTEGER, GL_UNSIGNED_INT,
                               &zero);
    const PcsHeader header{0, pcs_capacity, 0, 0};
    gl.NamedBufferSubData(pcs_buffer, 0, sizeof header, &header);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, count_buffer);

    const std::array<float, 16> m = view.clip_from_local();
    const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
    gl.UseProgram(abuffer_program);
    gl.UniformMatrix4fv(u_ab_clip, 1, GL_FALSE, m.data());
    gl.Uniform3f(u_ab_lo, float(lo.x()), float(lo.y()), float(lo.z()));
    gl.Uniform3f(u_ab_hi, float(hi.x()), float(hi.y()), float(hi.z()));
    gl.Uniform1i(u_ab_res, n);
    gl.Uniform1ui(u_ab_slots, view_slots);
    gl.BindFramebuffer(GL_FRAMEBUFFER, bare_fbo);
    gl.Viewport(0, 0, n, n);
    gl.Disable(GL_DEPTH_TEST);
    gl.Disable(GL_CULL_FACE);
    gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
    for (int i = 0; i < 6; ++i) gl.Enable(GL_CLIP_DISTANCE0 + i);
    gl.BindVertexArray(vao);
    for (int slot = 0; slot < 2; ++slot) {
      gl.Uniform1ui(u_ab_object, GLuint(slot));
      draw(slot, u_model_ab);
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    if (opt.resolve == Resolve::host || (opt.resolve == Resolve::automatic && software_renderer))
      return resolve_on_host(view, epsilon_world, opt, first_slot, fitting, view_slots, t_gpu, r, t);
    // The resolve reads what the draw stored through buffer textures (texture fetches).
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    ++passes_this_frame;
    check("the k-buffer draw");

    gl.UseProgram(resolve_program);
    gl.BindTextureUnit(0, count_tex);
    gl.BindTextureUnit(1, fragment_tex);
    for (int slot = 0; slot < 2; ++slot) {
      gl.TextureBuffer(corner_tex[slot], GL_RGBA32UI, slot_shape[slot] ? slot_shape[slot]->vbo : vbo[slot]);
      gl.BindTextureUnit(GLuint(2 + slot), corner_tex[slot]);
    }
    gl.Uniform1f(u_rs_eps, float(view.world_to_window_depth(epsilon_world)));
    gl.Uniform1f(u_rs_slope, float(opt.slope));
    gl.Uniform1i(u_rs_res, n);
    gl.Uniform1ui(u_rs_slots, view_slots);
    gl.Uniform1i(u_rs_full, opt.peel == PeelMode::full);
    gl.Uniform1ui(u_rs_first, GLuint(first_slot));
    gl.Uniform1i(u_rs_append, 1);
    gl.Uniform1i(u_rs_emit, -1);
    gl.DispatchCompute(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    ++passes_this_frame;
    check("the k-buffer resolve");
    PcsHeader got{};
    gl.GetNamedBufferSubData(pcs_buffer, 0, sizeof got, &got);
    if (got.max_fragments > view_slots) {
      t.gpu += ms_since(t_gpu);
      return regrow(got.max_fragments, fitting, view, epsilon_world, opt, first_slot, r, t);
    }
    r.layers = int(got.max_layers);
    r.passes = 1;
    if (captured) {
      captured->layers.clear();
      captured->epsilon_window = float(view.world_to_window_depth(epsilon_world));
      captured->slope = float(opt.slope);
      const GLuint zero[4] = {0, 0, 0, 0};
      gl.Uniform1i(u_rs_append, 0);
      ensure_layers(n);
      gl.BindImageTexture(2, layer_tex[0], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32UI);
      for (int k = 0; k < r.layers; ++k) {
        gl.ClearTexImage(layer_tex[0], 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, zero);
        gl.Uniform1i(u_rs_emit, k);
        gl.DispatchCompute(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
        gl.MemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        std::vector<std::uint32_t>& texels = captured->layers.emplace_back(std::size_t(n) * n * 4);
        gl.GetTextureImage(layer_tex[0], 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                           GLsizei(texels.size() * sizeof(std::uint32_t)), texels.data());
      }
      check("layer capture");
    }
    t.gpu += ms_since(t_gpu);
    return read_pcs(t, &got);
  }

  // A texel had `max_fragments`, more than the k-buffer's slots: grow it (with a quarter to
  // spare) and return false (peel again); deeper than any k-buffer that fits (`fitting` slots),
  // this view goes to multi-pass (`slots` stays).
  bool regrow(std::uint32_t max_fragments, std::size_t fitting, const RoiView& view, double epsilon_world,
              const DetectOptions& opt, int first_slot, PairResult& r, Timings& t) {
    const std::size_t wanted = std::min<std::size_t>(std::size_t(max_fragments) * 5 / 4, fitting);
    if (wanted < max_fragments) return peel(view, epsilon_world, opt, first_slot, r, t);
    slots = std::max(slots, std::uint32_t(wanted));
    return false;
  }

  // The second half of peel_single_pass() with Resolve::host: the k-buffer mapped (host memory
  // on a software renderer: no copy) and resolved by core/kbuffer.h into `pcs`.
  bool resolve_on_host(const RoiView& view, double epsilon_world, const DetectOptions& opt, int first_slot,
                       std::size_t fitting, std::uint32_t view_slots, Clock::time_point t_gpu, PairResult& r,
                       Timings& t) {
    const int n = view.resolution;
    const std::size_t texels = std::size_t(n) * std::size_t(n);
    ++passes_this_frame;
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
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const auto t_map = Clock::now();
    const auto* counts = static_cast<const std::uint32_t*>(
        gl.MapNamedBufferRange(count_buffer, 0, GLsizeiptr(texels * 4), GL_MAP_READ_BIT));
    const auto* fragments = static_cast<const KFragment*>(gl.MapNamedBufferRange(
        fragment_buffer, 0, GLsizeiptr(texels * view_slots * sizeof(KFragment)), GL_MAP_READ_BIT));
    const double map_ms = ms_since(t_map);  // a wait for the draw, then (llvmpipe) no copy
    t.readback += map_ms;
    if (!counts || !fragments) {
      if (counts) gl.UnmapNamedBuffer(count_buffer);
      if (fragments) gl.UnmapNamedBuffer(fragment_buffer);
      check("mapping the k-buffer");
      throw GlError("peelcd::gl::Pipeline: mapping the k-buffer failed");
    }
    KBuffer kb;
    kb.counts = counts;
    kb.fragments = fragments;
    kb.resolution = n;
    kb.slots = view_slots;
    KResolveParams p;
    p.epsilon_window = float(view.world_to_window_depth(epsilon_world));
    p.slope = float(opt.slope);
    p.full_peel = opt.peel == PeelMode::full;
    p.first_object = std::uint32_t(first_slot);
    p.ids[0] = ids[0];
    p.ids[1] = ids[1];
    pcs.clear();
    if (captured) {
      captured->layers.clear();
      captured->epsilon_window = p.epsilon_window;
      captured->slope = p.slope;
    }
    const KResolveResult got = resolver.resolve(kb, p, pcs, captured ? &captured->layers : nullptr);
    gl.UnmapNamedBuffer(count_buffer);
    gl.UnmapNamedBuffer(fragment_buffer);
    check("the host k-buffer resolve");
    t.gpu += ms_since(t_gpu) - map_ms;
    if (got.max_fragments > view_slots) return regrow(got.max_fragments, fitting, view, epsilon_world, opt, first_slot, r, t);
    r.layers = int(got.max_layers);
    r.passes = 1;
    if (!pcs.empty()) ++pcs_readbacks;  // the PCS reach the CPU (no list to read back here)
    return true;
  }

  // Reads the PCS list back into `pcs` (the header too, unless given); false if it overflowed
  // (grown; peel again).
  bool read_pcs(Timings& t, const PcsHeader* header = nullptr) {
    const auto t_read = Clock::now();
    PcsHeader got{};
    if (header)
      got = *header;
    else
      gl.GetNamedBufferSubData(pcs_buffer, 0, sizeof got, &got);
    if (got.count > pcs_capacity) {
      grow_pcs(got.count + got.count / 2);
      t.readback += ms_since(t_read);
      return false;
    }
    pcs.resize(got.count);
    if (got.count) {
      gl.GetNamedBufferSubData(pcs_buffer, sizeof(PcsHeader), GLsizeiptr(got.count) * 8, pcs.data());
      ++pcs_readbacks;
    }
    check("PCS readback");
    t.readback += ms_since(t_read);
    return true;
  }

  // Peels one ROI; fills `pcs` with the ID pairs read back. Returns false if the PCS buffer
  // overflowed (it has then been grown and the caller must peel again).
  bool peel(const RoiView& view, double epsilon_world, const DetectOptions& opt, int first_slot,
            PairResult& r, Timings& t) {
    const auto t_gpu = Clock::now();
    const int n = view.resolution;
    ensure_layers(n);
    const PcsHeader header{0, pcs_capacity, 0, 0};
    gl.NamedBufferSubData(pcs_buffer, 0, sizeof header, &header);
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);

    const std::array<float, 16> m = view.clip_from_local();
    const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
    gl.UseProgram(peel_program);
    gl.UniformMatrix4fv(u_clip, 1, GL_FALSE, m.data());
    gl.Uniform3f(u_box_lo, float(lo.x()), float(lo.y()), float(lo.z()));
    gl.Uniform3f(u_box_hi, float(hi.x()), float(hi.y()), float(hi.z()));
    gl.UseProgram(pcs_program);
    gl.Uniform1f(u_eps, float(view.world_to_window_depth(epsilon_world)));
    gl.Uniform1f(u_slope, float(opt.slope));
    gl.Uniform1i(u_track, opt.peel == PeelMode::full);
    if (opt.peel == PeelMode::full) {
      gl.ClearTexImage(run_tex, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, nullptr);
      gl.BindImageTexture(0, run_tex, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32UI);
    }
    gl.Uniform1i(u_res, n);

    gl.Viewport(0, 0, n, n);
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
    gl.Disable(GL_CULL_FACE);
    gl.ProvokingVertex(GL_LAST_VERTEX_CONVENTION);
    for (int i = 0; i < 6; ++i) gl.Enable(GL_CLIP_DISTANCE0 + i);
    gl.BindVertexArray(vao);

    const GLuint zero[4] = {0, 0, 0, 0};
    const GLfloat far_depth = 1.0f;
    r.layers = 0;
    r.passes = 0;
    if (captured) {
      captured->layers.clear();  // a rerun after a PCS overflow starts over
      captured->epsilon_window = float(view.world_to_window_depth(epsilon_world));
      captured->slope = float(opt.slope);
    }
    for (int k = 0; k < kMaxPasses; ++k) {
      const int cur = k & 1, prev = cur ^ 1;
      gl.BindFramebuffer(GL_FRAMEBUFFER, fbo[cur]);
      gl.ClearBufferuiv(GL_COLOR, 0, zero);
      gl.ClearBufferfv(GL_DEPTH, 0, &far_depth);
      gl.UseProgram(peel_program);
      gl.Uniform1i(u_has_prev, k > 0);
      gl.BindTextureUnit(0, layer_tex[prev]);
      gl.BeginQuery(GL_ANY_SAMPLES_PASSED, query);
      for (int i = 0; i < 2; ++i) {
        // Alternate: one object per pass, starting with `first_slot`. Full: both, every pass.
        const int slot = opt.peel == PeelMode::full ? i : (first_slot + k) & 1;
        if (opt.peel == PeelMode::alternate && i == 1) break;
        gl.Uniform1ui(u_object, GLuint(slot));
        draw(slot, u_model_peel);
      }
      gl.EndQuery(GL_ANY_SAMPLES_PASSED);
      ++r.passes;
      ++passes_this_frame;
      check("a peel pass");
      GLuint any = 0;
      gl.GetQueryObjectuiv(query, GL_QUERY_RESULT, &any);
      if (!any) break;  // the whole ROI ended
      ++r.layers;
      if (captured) {
        std::vector<std::uint32_t>& texels = captured->layers.emplace_back(std::size_t(n) * n * 4);
        gl.GetTextureImage(layer_tex[cur], 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                           GLsizei(texels.size() * sizeof(std::uint32_t)), texels.data());
        check("layer capture");
      }
      if (k == 0) continue;
      gl.UseProgram(pcs_program);
      gl.BindTextureUnit(0, layer_tex[prev]);
      gl.BindTextureUnit(1, layer_tex[cur]);
      gl.DispatchCompute(GLuint((n + 7) / 8), GLuint((n + 7) / 8), 1);
      // The next dispatch reads run_start and appends to the same buffer.
      gl.MemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
      ++passes_this_frame;
      check("a PCS pass");
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    t.gpu += ms_since(t_gpu);
    return read_pcs(t);
  }
};

Pipeline::Pipeline(Context& context) : impl_(std::make_unique<Impl>(context)) {}
Pipeline::~Pipeline() = default;
std::string Pipeline::renderer() const { return impl_->renderer; }
std::string Pipeline::version() const { return impl_->version; }
int Pipeline::max_resolution() const { return impl_->max_texture; }
void Pipeline::capture_layers(std::vector<CapturedView>* sink) { impl_->capture = sink; }
std::string shader_sources_hash() { return shaders::shader_sources_hash; }

FrameResult Pipeline::detect(const std::vector<Object>& objects, const DetectOptions& opt) {
  FrameResult out;
  detect(objects, opt, out);
  return out;
}

void Pipeline::detect(const std::vector<Object>& objects, const DetectOptions& opt, FrameResult& out) {
  Impl& s = *impl_;
  if (opt.resolution < 0 || opt.resolution > s.max_texture)
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): resolution " +
                                std::to_string(opt.resolution) + " is outside 1.." +
                                std::to_string(s.max_texture) + " (GL_MAX_TEXTURE_SIZE)");
  if (opt.resolution == 0 && (opt.budget <= 0 || opt.budget > s.max_texture))
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): budget " + std::to_string(opt.budget) +
                                " is outside 1.." + std::to_string(s.max_texture));
  if (opt.views < 1 || opt.views > 3)
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): views must be 1, 2 or 3");
  if (!(opt.slope >= 0.0) || !std::isfinite(opt.slope))
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): slope must be finite and >= 0");
  if (!(opt.epsilon >= 0.0) || !std::isfinite(opt.epsilon))
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): epsilon must be finite and >= 0 (0 = one texel)");
  if (!(opt.edge_texels >= 0.0) || !std::isfinite(opt.edge_texels))
    throw std::invalid_argument("peelcd::gl::Pipeline::detect(): edge_texels must be finite and >= 0 (0 = the budget's share)");

  // A layer texel stores object << 31 | ID + 1 (shaders/peel.frag): IDs must stay below 2^31 - 1.
  for (const Object& o : objects)
    if (std::max(o.mesh.triangles.size(), o.mesh.vertices.size()) >= 0x7fffffffu)
      throw std::invalid_argument("peelcd::gl::Pipeline::detect(): object '" + o.name +
                                  "' has 2^31 - 1 or more triangles or vertices; IDs hold 31 bits");

  // `out` is reused: its vectors keep their capacity, so a steady stream of frames allocates
  // nothing here (tests/alloc/test_alloc.cpp counts it).
  if (out.renderer != s.renderer) out.renderer = s.renderer;
  out.timings = Timings{};
  out.gl_passes = out.rois_peeled = out.triangles_uploaded = out.triangles_indexed = out.shape_uploads = 0;
  out.pcs_readbacks = 0;
  s.passes_this_frame = 0;
  s.pcs_readbacks = 0;
  s.shape_uploads = 0;
  const auto t_total = Clock::now();

  auto t0 = Clock::now();
  std::vector<Aabb>& boxes = s.boxes;
  boxes.clear();
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  overlapping_pairs(boxes, s.object_pairs, s.order);
  const auto& pairs = s.object_pairs;
  out.timings.aabb = ms_since(t0);

  if (!pairs.empty()) {
    s.context.make_current();
    s.drop_expired_shapes();
  }
  const int n = opt.resolution > 0 ? opt.resolution : tile_resolution(opt.budget, pairs.size());
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);

  std::size_t used = 0;
  for (const auto& [ia, ib] : pairs) {
    if (used == out.pairs.size()) out.pairs.emplace_back();
    PairResult& r = out.pairs[used++];
    r.pcs.clear();
    r.colliding.clear();
    r.layers = r.passes = 0;
    r.pcs_count = r.candidates = 0;
    r.triangles_drawn_a = r.triangles_drawn_b = 0;
    r.object_a = ia;
    r.object_b = ib;
    r.roi = intersection(boxes[ia], boxes[ib]);
    r.region = r.roi;
    r.triangles_in_roi_a = r.triangles_in_roi_b = 0;
    r.resolution = n;
    const Mesh& ma = objects[ia].mesh;
    const Mesh& mb = objects[ib].mesh;
    const std::vector<std::uint32_t>*only_a = nullptr, *only_b = nullptr;
    if (opt.cull == Cull::contact) {
      t0 = Clock::now();
      const int tile = s.cull_pair(ma, mb, r.roi, opt, n);
      out.timings.aabb += ms_since(t0);
      r.region = s.cull.box;
      r.triangles_in_roi_a = s.cull.stats.in_roi_a;
      r.triangles_in_roi_b = s.cull.stats.in_roi_b;
      if (tile == 0) continue;  // no triangle of one object near the other: no contact
      only_a = &s.cull.kept_a;
      only_b = &s.cull.kept_b;
      r.resolution = tile;
    }
    std::vector<IdPair>& all_pcs = s.pcs_all;
    all_pcs.clear();
    for (std::size_t v = 0; v < frame_count; ++v) {
      const RoiView view = make_padded_roi_view(r.region, boxes[ia], boxes[ib], frames[v], r.resolution);
      if (v == 0) r.epsilon = opt.epsilon > 0.0 ? opt.epsilon : view.texel();

      t0 = Clock::now();
      // Each view gathers its own triangles: the pad follows that view's texel size.
      const double min_a = s.prepare(objects[ia], view, only_a, opt.ids, 0);
      const double min_b = s.prepare(objects[ib], view, only_b, opt.ids, 1);
      if (v == 0) {
        r.triangles_drawn_a = s.corners(0) / 3;
        r.triangles_drawn_b = s.corners(1) / 3;
        if (opt.cull == Cull::box) {  // nothing culled: what touches the (padded) ROI
          r.triangles_in_roi_a = r.triangles_drawn_a;
          r.triangles_in_roi_b = r.triangles_drawn_b;
        }
        r.a_first = min_a > min_b;  // the farther object first; ties: B first
      }
      if (s.corners(0) == 0 || s.corners(1) == 0) {
        out.timings.upload += ms_since(t0);
        continue;  // one object has nothing in the ROI: no contact possible, no GL work
      }
      s.upload(0);
      s.upload(1);
      out.timings.upload += ms_since(t0);
      for (int slot = 0; slot < 2; ++slot)
        (s.slot_shape[slot] ? out.triangles_indexed : out.triangles_uploaded) += s.corners(slot) / 3;
      ++out.rois_peeled;

      PairResult one;
      if (s.capture) {
        s.captured = &s.capture->emplace_back();
        s.captured->pair = used - 1;
        s.captured->view = int(v);
        s.captured->roi = view;
        s.captured->a_first = min_a > min_b;
      }
      const int first = min_a > min_b ? 0 : 1;
      if (opt.peeler == Peeler::abuffer) {
        while (!s.peel_single_pass(view, r.epsilon, opt, first, one, out.timings)) {
        }
      } else {
        while (!s.peel(view, r.epsilon, opt, first, one, out.timings)) {
        }
      }
      if (s.captured) {
        s.captured->pcs = s.pcs;
        std::sort(s.captured->pcs.begin(), s.captured->pcs.end());
        s.captured->pcs.erase(std::unique(s.captured->pcs.begin(), s.captured->pcs.end()), s.captured->pcs.end());
        s.captured = nullptr;
      }
      r.layers = std::max(r.layers, one.layers);
      r.passes += one.passes;
      all_pcs.insert(all_pcs.end(), s.pcs.begin(), s.pcs.end());
    }
    if (r.triangles_drawn_a == 0 || r.triangles_drawn_b == 0) continue;

    t0 = Clock::now();
    // Sorted and unique through the radix sort of packed pairs (the views repeat most PCS).
    s.pcs_keys.clear();
    for (const IdPair& p : all_pcs) s.pcs_keys.push_back(pack_pair(p.a, p.b));
    sort_unique_pairs(s.pcs_keys, s.candidate_scratch);
    all_pcs.clear();
    for (const std::uint64_t k : s.pcs_keys) all_pcs.push_back(IdPair{pair_a(k), pair_b(k)});
    r.pcs_count = all_pcs.size();
    r.pcs.assign(all_pcs.begin(), all_pcs.end());
    s.map_a.rebuild(ma, opt.ids);
    s.map_b.rebuild(mb, opt.ids);
    s.candidates.clear();
    expand_pcs(all_pcs, s.map_a, s.map_b, s.candidates, s.candidate_scratch);
    r.candidates = s.candidates.size();
    narrow_phase(ma, mb, s.candidates, r.colliding);
    out.timings.cpu += ms_since(t0);
  }
  out.pairs.resize(used);
  out.gl_passes = s.passes_this_frame;
  out.pcs_readbacks = s.pcs_readbacks;
  out.shape_uploads = s.shape_uploads;
  out.timings.total = ms_since(t_total);
}

double Pipeline::floor_ms(const std::vector<Object>& objects, const DetectOptions& opt,
                          std::vector<double>* per_view) {
  Impl& s = *impl_;
  if (per_view) per_view->assign(std::size_t(std::max(opt.views, 0)), 0.0);
  std::vector<Aabb> boxes;
  for (const Object& o : objects) boxes.push_back(bounds(o.mesh));
  const auto pairs = overlapping_pairs(boxes);
  if (pairs.empty()) return 0.0;
  s.context.make_current();
  const int n = opt.resolution > 0 ? opt.resolution : tile_resolution(opt.budget, pairs.size());
  ViewFrame frames[3];
  const std::size_t frame_count = fused_view_frames(opt, frames);
  double ms = 0.0;
  for (const auto& [ia, ib] : pairs) {
    Aabb roi = intersection(boxes[ia], boxes[ib]);
    const std::vector<std::uint32_t>*only_a = nullptr, *only_b = nullptr;
    int tile = n;
    if (opt.cull == Cull::contact) {  // the triangles and tile detect() would draw (culling not timed)
      tile = s.cull_pair(objects[ia].mesh, objects[ib].mesh, roi, opt, n);
      if (tile == 0) continue;
      roi = s.cull.box;
      only_a = &s.cull.kept_a;
      only_b = &s.cull.kept_b;
    }
    for (std::size_t v = 0; v < frame_count; ++v) {
      const RoiView view = make_padded_roi_view(roi, boxes[ia], boxes[ib], frames[v], tile);
      s.prepare(objects[ia], view, only_a, opt.ids, 0);
      s.prepare(objects[ib], view, only_b, opt.ids, 1);
      if (s.corners(0) == 0 || s.corners(1) == 0) continue;
      s.upload(0);
      s.upload(1);
      s.ensure_layers(tile);
      s.gl.Finish();
      const auto t0 = Clock::now();
      const std::array<float, 16> m = view.clip_from_local();
      const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
      s.gl.UseProgram(s.floor_program);
      s.gl.UniformMatrix4fv(s.u_floor_clip, 1, GL_FALSE, m.data());
      s.gl.Uniform3f(s.u_floor_lo, float(lo.x()), float(lo.y()), float(lo.z()));
      s.gl.Uniform3f(s.u_floor_hi, float(hi.x()), float(hi.y()), float(hi.z()));
      s.gl.BindFramebuffer(GL_FRAMEBUFFER, s.fbo[0]);
      s.gl.Viewport(0, 0, tile, tile);
      s.gl.Enable(GL_DEPTH_TEST);
      s.gl.DepthFunc(GL_LESS);
      for (int i = 0; i < 6; ++i) s.gl.Enable(GL_CLIP_DISTANCE0 + i);
      const GLfloat far_depth = 1.0f;
      s.gl.ClearBufferfv(GL_DEPTH, 0, &far_depth);
      s.gl.BindVertexArray(s.vao);
      for (int slot = 0; slot < 2; ++slot) s.draw(slot, s.u_model_floor);
      s.gl.Finish();
      const double view_ms = ms_since(t0);
      ms += view_ms;
      if (per_view) (*per_view)[v] += view_ms;
      s.gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
      s.check("the floor draw");
    }
  }
  return ms;
}

}  // namespace peelcd::gl
