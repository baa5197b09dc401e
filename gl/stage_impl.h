#pragma once
// Private to the GL image stage: its state, shared by the files of gl/ that implement it.
//   programs.cpp     loading GL, compiling and linking the programs, checking errors
//   resources.cpp    layer textures, framebuffers, the k-buffer and the PCS buffer (grown, reused)
//   geometry.cpp     a view's triangles into buffers: ROI-local corners, or a rigid shape's indices
//   multipass.cpp    the multi-pass peeler (one draw per layer) and the PCS readback
//   single_pass.cpp  the single-pass peeler (k-buffer), its GPU and host resolves
//   batch.cpp        views packed into one k-buffer and one draw: gathered, uploaded, selected, drawn
//   batch_resolve.cpp  a drawn batch resolved: on the host, or by one dispatch (deep texels' rows)
//   pass_timers.cpp  the clocks: GPU timer queries per pass, the host's time blocked in GL reads
//   gl_stage.cpp     the public class, its one-view entry (peel_one), the floor draw
#include "peelcd/core/image/image_stage.h"
#include "peelcd/core/clock.h"
#include "peelcd/core/image/kbuffer.h"
#include "peelcd/core/worker_pool.h"
#include "peelcd/gl/gl_stage.h"

#include <glad/gl.h>

#include <array>
#include <chrono>
#include <initializer_list>
#include <map>
#include <unordered_map>
#include <memory>
#include <string>
#include <vector>

#include "shaders_embedded.h"  // the embedded sources (gl/CMakeLists.txt lists them)

namespace peelcd::gl {

// A shader's source as compiled: `defines` after its #version line, and the shared PCS tests
// (include/peelcd/core/image/pcs_test.inc) where it says #include "peelcd/core/image/pcs_test.inc".
std::string shader_source(const char* src, const std::string& defines = "");

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

// The batched resolves' header (shaders/conservative_batch_resolve.comp, abuffer_resolve.comp with
// PEELCD_BATCH): PcsHeader's words, the couples the certified filter dropped, padding to 32 bytes.
struct BatchPcsHeader {
  std::uint32_t count, capacity, max_layers, max_fragments, couples_apart, pad[3];
};

// Header of the deep texels' rows (DeepRows in shaders/conservative_batch_resolve.comp).
struct DeepHeader {
  std::uint32_t row_count, row_capacity, max_blocks, deep_texels;
};

// The kinds of GPU pass the stage times (Timings::gpu_raster, gpu_compute, gpu_transfer); select
// and cover are compute passes counted apart too (Timings::gpu_select, gpu_cover).
enum class GpuPass { raster, compute, select, cover, transfer };

// GL_TIME_ELAPSED queries around the stage's passes (pass_timers.cpp), when `on`: begin() before
// a pass's GL call and end() after it (queries of one target do not nest, so a pass is one call
// or a run of calls of one kind); collect() adds the finished ones to a Timings and reuses them.
class PassTimers {
 public:
  bool on = false;
  void bind(GladGLContext& gl) { gl_ = &gl; }
  void begin(GpuPass kind);
  void end();
  void collect(Timings& t);
  void release();

 private:
  GladGLContext* gl_ = nullptr;
  std::vector<GLuint> pool_;
  std::vector<GpuPass> kinds_;
  std::size_t used_ = 0;
  bool open_ = false;
  Clock::time_point first_;  // the first begin() since the last collect()
};

// One timed pass, for a scope.
class TimedPass {
 public:
  TimedPass(PassTimers& timers, GpuPass kind) : timers_(timers) { timers_.begin(kind); }
  ~TimedPass() { timers_.end(); }
  TimedPass(const TimedPass&) = delete;
  TimedPass& operator=(const TimedPass&) = delete;

 private:
  PassTimers& timers_;
};

// Host time blocked in a GL read (a read back, a map, a query result), for a scope: added to
// `ms` (the stage's wait_ms, handed to Timings::gl_wait).
class GlWait {
 public:
  explicit GlWait(double& ms) : ms_(ms), t0_(Clock::now()) {}
  ~GlWait() { ms_ += ms_since(t0_); }
  GlWait(const GlWait&) = delete;
  GlWait& operator=(const GlWait&) = delete;

 private:
  double& ms_;
  Clock::time_point t0_;
};

// Peel passes per ROI before giving up; each pass strictly increases every live texel's depth,
// so only a scene with more than this many surfaces along one ray reaches it.
constexpr int kMaxPasses = 4096;

// The programs, one struct per family: its GL program and its uniforms' locations
// (programs.cpp compiles them and locates the uniforms by the names in their sources).
// shaders/peel.vert + peel.frag: the multi-pass peeler's draw.
struct PeelProgram {
  GLuint id = 0;
  GLint clip = -1, box_lo = -1, box_hi = -1, has_prev = -1, object = -1, rank_flip = -1, model = -1;
};
// shaders/pcs.comp: the PCS test between two peeled layers.
struct PcsProgram {
  GLuint id = 0;
  GLint eps = -1, slope = -1, res = -1, track = -1;
};
// The floor (benchmarks): shaders/peel.vert and a fragment shader that does nothing.
struct FloorProgram {
  GLuint id = 0;
  GLint clip = -1, lo = -1, hi = -1, model = -1;
};
// shaders/peel.vert + abuffer.frag: the single-pass peeler's draw into the k-buffer.
struct ABufferProgram {
  GLuint id = 0;
  GLint clip = -1, lo = -1, hi = -1, object = -1, res = -1, slots = -1, model = -1;
};
// shaders/abuffer_resolve.comp: the single-pass peeler's GPU resolve.
struct ResolveProgram {
  GLuint id = 0;
  GLint eps = -1, slope = -1, res = -1, full = -1, first = -1, append = -1, emit = -1, slots = -1;
};
// shaders/conservative.{vert,geom,frag}: the conservative draw into the k-buffer.
struct ConservativeProgram {
  GLuint id = 0;
  GLint clip = -1, model = -1, res = -1, slots = -1, object = -1, grow_texels = -1, grow_depth = -1;
};
// shaders/conservative_resolve.comp: its GPU resolve.
struct ConservativeResolveProgram {
  GLuint id = 0;
  GLint res = -1, slots = -1, append = -1, emit = -1;
};
// shaders/conservative_cover.comp: the compute path's coverage (GlOptions::coverage compute),
// one-view (one object a dispatch) and batched (PEELCD_BATCH: a program per pass).
struct CoverProgram {
  GLuint id = 0;
  GLint row = -1;  // batched only (the one-view program reads its parameters from a buffer)
};
// A batched draw (the conservative or point-sampled sources with PEELCD_BATCH): a count pass
// and a fill pass over every view of a frame.
struct BatchDrawProgram {
  GLuint id = 0;
  GLint viewport = -1, count_only = -1;
};
// A batch's GPU resolve (shaders/conservative_batch_resolve.comp, abuffer_resolve.comp with
// PEELCD_BATCH): one dispatch over the packed k-buffer.
struct BatchResolveProgram {
  GLuint id = 0;
  GLint texels = -1;
};
// The conservative batch resolve of texels deeper than PEELCD_GPU_RESOLVE_DEPTH (the same source
// with PEELCD_DEEP): their rows (texel, block of fragments) in batch.deep_rows.
struct DeepProgram {
  GLuint id = 0;
  GLint texels = -1, row_base = -1;
};
// shaders/batch_select.comp: the batch's GPU selection of rigid objects' triangles.
struct SelectProgram {
  GLuint id = 0;
  GLint jobs = -1, invocations = -1, row = -1, pass = -1, conservative = -1;
};
// shaders/prefix_sum.comp: the prefix sum of the count pass's counts.
struct PrefixSumProgram {
  GLuint id = 0;
  GLint texels = -1, blocks = -1, pass = -1;
};

// The bytes of a batch's draw entry or selection job (four 32-bit words; batch.cpp writes them,
// batch_resolve.cpp reads the selected ones back).
constexpr std::size_t kBatchEntryBytes = 4 * sizeof(std::uint32_t);

// The batched views' state (batch.cpp), owned by the batch: its GL buffers (grown, reused) and
// the host's copies of what it uploads or reads back.
struct BatchState {
  // The geometry: per view, its matrices (views); the draw's entries (one per triangle: first
  // corner, view << 1 | object, provoking ID); the corners of deforming objects' triangles,
  // uploaded per frame (frame); the selection pass's jobs (per view and rigid object) and the
  // indirect draw's command. Nothing in the vertex array: an empty one.
  GLuint frame = 0, views = 0, entries = 0, jobs = 0, command = 0, vao = 0;
  std::size_t frame_capacity = 0, views_capacity = 0, entries_capacity = 0, jobs_capacity = 0;  // bytes
  std::vector<GpuVertex> corners;
  // The moving meshes' vertices (world-space floats, three a vertex), once a batch: each mesh's
  // first vertex there, in the order met; written into the buffer through a mapping
  // (upload_batch()), not staged on the host.
  GLuint positions = 0;
  std::size_t positions_capacity = 0, position_count = 0;  // bytes; vertices this batch
  std::unordered_map<const Mesh*, std::uint32_t> moving_bases;
  std::vector<const Mesh*> moving_order;
  // Entries: first corner, view << 1 | object, provoking ID, a moving mesh's positions + 1 (or
  // 0). Selection jobs: two records each (shaders/batch_select.comp).
  std::vector<std::array<std::uint32_t, 4>> entry_data, job_data;
  std::vector<std::uint32_t> ids;  // the provoking ID by draw order (the host resolve's)
  std::vector<float> view_data;
  // The selection pass's staged triangles (pass 0's, before the contact-region rounds) and the
  // objects' regions per view (16 words a view, uploaded per frame: what the host knows of them,
  // and whether the selection picks each object's triangles).
  // The contact grid: per view and object, which of 16^3 cells over the view's region its
  // triangles reach (shaders/batch_select.comp), cleared per batch.
  GLuint staged = 0, regions = 0, grid = 0;
  std::size_t staged_capacity = 0, regions_capacity = 0, grid_capacity = 0;  // bytes
  std::vector<std::uint32_t> region_data;
  // The count pass's counts and their prefix sums (the compact packed k-buffer's offsets): on the
  // host for the host resolve, else by shaders/prefix_sum.comp (per block of 1024 texels its sum
  // in scan_blocks, the total in scan_total: only that comes back).
  GLuint offset_buffer = 0, scan_blocks = 0, scan_total = 0;
  std::size_t offsets_capacity = 0, scan_blocks_capacity = 0;  // bytes
  std::vector<std::uint32_t> counts, offsets;
  std::uint32_t deepest = 0;
  // The GPU resolve's per-view depths (layers) and what it reads back.
  GLuint layers = 0;
  std::size_t layers_capacity = 0;  // bytes
  std::vector<std::uint32_t> view_layers, pairs;
  // The deep texels' rows (texel, block of fragments), behind a DeepHeader.
  GLuint deep_rows = 0;
  std::size_t deep_rows_capacity = 0;  // rows
};

struct GlImageStage::Impl {
  std::shared_ptr<Context> context;
  GlOptions options;
  GladGLContext gl{};
  std::string backend, renderer, version;
  GLint max_texture = 0;
  std::size_t max_storage_block = 0;  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE, bytes
  bool software_renderer = false;     // GL runs on the CPU: Resolve::automatic resolves on the host
  // A rigid object's triangles in a view selected on the host (job_triangles(): a job without
  // its list drawn alone, or by the host's selection in a batch), per slot.
  std::vector<std::uint32_t> selected[2];
  // The stage's counters (GlImageStage::counters): every draw, dispatch, upload and readback.
  StageCounters* counters = nullptr;
  void count_upload(std::size_t bytes) { counters->bytes_uploaded += bytes; }
  void count_geometry(std::size_t bytes) {  // mesh data: corners, indices, draw entries
    counters->bytes_uploaded += bytes;
    counters->geometry_bytes += bytes;
  }
  void count_read(std::size_t bytes) {
    ++counters->readbacks;
    counters->bytes_read += bytes;
  }
  void count_draw() { ++counters->draws; }
  void count_dispatch() { ++counters->dispatches; }
  // The clocks (pass_timers.cpp): GPU passes, and the host's time blocked in GL reads; handed to
  // the caller's Timings when a peel() or peel_batch() returns.
  PassTimers timers;
  double wait_ms = 0.0;
  void hand_clocks(Timings& t);
  // The stage's GL work goes through these: counted (StageCounters), and timed with pass timing
  // (draws: raster; dispatches: compute; uploads, clears, copies: transfer); reads count the
  // host's wait.
  template <class Draw>
  void timed_draw(const Draw& draw_call) {
    const TimedPass pass(timers, GpuPass::raster);
    draw_call();
    count_draw();
  }
  void dispatch(GLuint x, GLuint y, GLuint z, GpuPass kind = GpuPass::compute) {
    const TimedPass pass(timers, kind);
    gl.DispatchCompute(x, y, z);
    count_dispatch();
  }
  void upload_buffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, const void* data) {
    const TimedPass pass(timers, GpuPass::transfer);
    gl.NamedBufferSubData(buffer, offset, bytes, data);
    count_upload(std::size_t(bytes));
  }
  void upload_geometry(GLuint buffer, GLintptr offset, GLsizeiptr bytes, const void* data) {
    const TimedPass pass(timers, GpuPass::transfer);
    gl.NamedBufferSubData(buffer, offset, bytes, data);
    count_geometry(std::size_t(bytes));
  }
  void clear_buffer(GLuint buffer, GLsizeiptr bytes) {  // the first `bytes` to zero words
    const TimedPass pass(timers, GpuPass::transfer);
    const GLuint zero = 0;
    gl.ClearNamedBufferSubData(buffer, GL_R32UI, 0, bytes, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  void copy_buffer(GLuint from, GLuint to, GLintptr read_offset, GLintptr write_offset, GLsizeiptr bytes) {
    const TimedPass pass(timers, GpuPass::transfer);
    gl.CopyNamedBufferSubData(from, to, read_offset, write_offset, bytes);
  }
  // A memory barrier: free on a GPU, but a software renderer (llvmpipe) finishes the work before
  // it, so its time counts as a wait.
  void barrier(GLbitfield bits) {
    const GlWait wait(wait_ms);
    gl.MemoryBarrier(bits);
  }
  void read_buffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, void* data) {
    const GlWait wait(wait_ms);
    gl.GetNamedBufferSubData(buffer, offset, bytes, data);
    count_read(std::size_t(bytes));
  }
  void read_texture(GLuint texture, std::vector<std::uint32_t>& texels) {  // RGBA32UI, level 0
    const GlWait wait(wait_ms);
    gl.GetTextureImage(texture, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, GLsizei(texels.size() * sizeof(std::uint32_t)),
                       texels.data());
    count_read(texels.size() * sizeof(std::uint32_t));
  }
  const void* map_for_reading(GLuint buffer, std::size_t bytes) {  // null: the map failed
    const GlWait wait(wait_ms);
    const void* data = gl.MapNamedBufferRange(buffer, 0, GLsizeiptr(bytes), GL_MAP_READ_BIT);
    count_read(bytes);
    return data;
  }

  // Programs (one struct per family: its ID and uniforms).
  PeelProgram peel;
  PcsProgram pcs;
  FloorProgram floor_draw;
  ABufferProgram abuffer;
  ResolveProgram resolve;
  ConservativeProgram cons;
  ConservativeResolveProgram cons_resolve;
  BatchDrawProgram cons_batch, point_batch;
  CoverProgram cover, cover_batch[2];  // [1]: the batch's count pass, [0]: its fill pass
  // [1]: with the certified filter (PEELCD_FILTER_APART; GlOptions::gpu_filter), [0] without.
  BatchResolveProgram cons_batch_resolve[2], point_batch_resolve;
  DeepProgram cons_deep[2];
  SelectProgram select;
  PrefixSumProgram prefix_sum;
  BatchState batch;
  std::size_t read_batch_counts(std::size_t texels, Timings& t);

  // Rigid shapes and moving meshes' triangles resident for the batch: one buffer holding every
  // shape a batch drew (its corners, with IDs, copied GPU to GPU from the shape's cached buffer:
  // uploaded once) and every moving mesh's corner records (vertex, ID; uploaded once per
  // topology), each at its first corner; kept while some object holds the shape or topology,
  // compacted when the buffer grows (batch.cpp).
  struct ResidentShape {
    std::weak_ptr<const void> owner;
    std::size_t base = 0, corners = 0;
  };
  std::map<std::pair<const void*, IdMode>, ResidentShape> resident;
  GLuint resident_buffer = 0;
  std::size_t resident_capacity = 0, resident_used = 0;  // corners
  std::size_t resident_base(const std::shared_ptr<const Mesh>& shape, IdMode ids);
  std::size_t resident_topology(const MovingMesh& moving, IdMode ids);
  std::uint32_t moving_positions(const Mesh& mesh);
  void upload_positions();
  std::size_t resident_reserve(const std::pair<const void*, IdMode>& key, const std::shared_ptr<const void>& owner,
                               std::size_t corners);
  static bool moving_mesh(const Object& o) { return !(o.rigid && o.rigid->shape) && o.moving && o.moving->source && o.moving->topology; }

  // Geometry: per slot (0 = A, 1 = B), the corners of a world-space object's triangles in the
  // view (`staging`, uploaded to `vbo`), or a rigid object's cached shape and the corner indices
  // of its triangles in the view (`indices`, uploaded to `ibo`).
  GLuint vao = 0, vbo[2] = {0, 0}, ibo[2] = {0, 0};
  std::size_t vbo_capacity[2] = {0, 0};  // in vertices
  std::size_t ibo_capacity[2] = {0, 0};
  std::vector<GpuVertex> staging[2];
  std::vector<std::uint32_t> indices[2];
  struct CachedShape {
    std::weak_ptr<const Mesh> owner;
    GLuint vbo = 0;
    std::size_t corners = 0;  // in the VBO: 3 per triangle of the shape
    // Each triangle's provoking-corner ID (the host resolve's; an indexed draw's order is the
    // shape's triangle index, gl_VertexID / 3 of its corners 3t + k).
    std::vector<std::uint32_t> provoking_ids;
  };
  std::map<std::pair<const Mesh*, IdMode>, CachedShape> shapes;
  const CachedShape* slot_shape[2] = {nullptr, nullptr};
  std::array<float, 16> slot_model[2];
  std::size_t shape_uploads = 0;  // during the current job

  // Multi-pass peeling: two ping-pong layer textures sharing one depth buffer, the run-start
  // texture of full peeling, the occlusion query that ends a ROI.
  GLuint layer_tex[2] = {0, 0}, run_tex = 0, depth_rb = 0, fbo[2] = {0, 0}, bare_fbo = 0;
  int layer_size = 0, bare_size = 0;
  GLuint query = 0;
  // The PCS append buffer (both peelers).
  GLuint pcs_buffer = 0;
  std::uint32_t pcs_capacity = 0;
  // The k-buffer of the single-pass peeler (shaders/abuffer.frag): per-texel fragment counts
  // and up to `slots` fragments of 16 bytes per texel; the resolve reads both, and the corners
  // the objects were drawn from, through buffer textures.
  GLuint count_buffer = 0, fragment_buffer = 0, count_tex = 0, fragment_tex = 0, corner_tex[2] = {0, 0};
  GLint max_texture_buffer = 0;  // GL_MAX_TEXTURE_BUFFER_SIZE, texels
  std::uint32_t slots = 16;
  std::size_t kbuffer_texels = 0, kbuffer_fragments = 0;
  // The host resolve (Resolve::host): triangle ID by draw order per slot, and the threads.
  std::vector<std::uint32_t> ids_by_order[2];
  WorkerPool pool;
  KResolver resolver{pool};

  Impl(std::shared_ptr<Context> ctx, const GlOptions& opt);  // programs.cpp
  ~Impl();

  // programs.cpp
  void build_programs();
  // The compute coverage's three programs, built for options.cover_share_texels (their define):
  // again when that changed since (ensure_cover_programs(), called with the context current).
  void link_cover_programs();
  void ensure_cover_programs() {
    if (cover_share_linked != cover_share()) link_cover_programs();
  }
  int cover_share_linked = -2;  // none linked yet
  // The threshold the programs are built for (below 0: no sharing).
  int cover_share() const {
    const int s = options.cover_share_texels;
    if (s == -1) return software_renderer ? -1 : 16;
    return s < 0 ? -1 : s;
  }
  void locate_uniforms();
  void create_objects();
  void check(const char* where);
  GLuint compile(GLenum type, const char* src, const char* name);
  GLuint link(std::initializer_list<GLuint> stages, const char* name);

  // resources.cpp
  void grow_pcs(std::uint32_t capacity);
  std::size_t fitting_slots(std::size_t texels) const;
  std::size_t fetchable() const;
  void ensure_kbuffer(std::size_t texels, std::size_t view_slots);
  void ensure_fragments(std::size_t fragments);  // the fragment buffer holds at least this many
  void release_layers();
  void ensure_layers(int n);
  void ensure_bare_fbo(int n);

  // geometry.cpp
  void prepare(const Object& object, const RoiView& view, const std::vector<std::uint32_t>& triangles, IdMode ids,
               int slot);
  const CachedShape& cached_shape(const std::shared_ptr<const Mesh>& shape, IdMode ids);
  void drop_expired_shapes();
  void draw(int slot, GLint u_model);
  void upload(int slot);
  // Corners in the VBO a slot draws from (its triangles in the view, or a rigid shape's all).
  std::size_t vbo_corners(int slot) const {
    return slot_shape[slot] ? slot_shape[slot]->corners : staging[slot].size();
  }
  // Corners slot `slot` draws for the current view.
  std::size_t corners(int slot) const { return slot_shape[slot] ? indices[slot].size() : staging[slot].size(); }
  void set_view_uniforms(GLint u_clip_, GLint u_lo, GLint u_hi, const RoiView& view);

  // multipass.cpp: peels the job; false if the PCS buffer overflowed (grown: peel again).
  bool peel_multipass(const PeelJob& job, PeelResult& out, Timings& t);
  bool read_pcs(PeelResult& out, Timings& t, const PcsHeader* header = nullptr);

  // single_pass.cpp: the same contract.
  bool peel_single_pass(const PeelJob& job, PeelResult& out, Timings& t);
  void start_kbuffer(int n, std::uint32_t view_slots);
  void bind_resolve_inputs();
  void capture_resolved(int n, int layers, GLint u_append, GLint u_emit, PeelResult& out);
  bool regrow(std::uint32_t max_fragments, std::size_t fitting, const PeelJob& job, PeelResult& out, Timings& t);
  // With the resolve program in use and its uniforms set: dispatches it over the n x n view,
  // then regrows (false) or captures and reads the PCS back (both single-pass peelers).
  bool dispatch_resolve(const PeelJob& job, std::size_t fitting, std::uint32_t view_slots, Clock::time_point t_gpu,
                        GLint u_append, GLint u_emit, const char* what, PeelResult& out, Timings& t);
  // Conservative mode (shaders/conservative.*): false as peel_single_pass(); a view deeper than
  // any k-buffer that fits is marked PeelResult::exhaustive.
  bool peel_conservative(const PeelJob& job, PeelResult& out, Timings& t);
  void cover_one_view(int slot, const std::array<float, 16>& clip, int n, std::uint32_t view_slots, float grow_x,
                      float grow_z);
  GLuint cover_params = 0;  // cover_one_view()'s parameters (256 bytes per object)
  bool resolve_on_host(const PeelJob& job, std::size_t fitting, std::uint32_t view_slots, Clock::time_point t_gpu,
                       PeelResult& out, Timings& t);

  // batch.cpp: views jobs[0..count) (all conservative, or all point-sampled) packed into one
  // k-buffer and drawn at once, resolved on the host or by one dispatch. Returns how many of the
  // jobs it peeled (at least one: a first job that does not fit a packed k-buffer alone is
  // peeled by peel_one()).
  // One view: its geometry uploaded, then peeled by the configured peeler (GlImageStage::peel).
  void peel_one(const PeelJob& job, PeelResult& out, Timings& timings);
  std::size_t peel_batched_views(const PeelJob* jobs, std::size_t count, PeelResult* outs, Timings& t);
  // Its steps, in order (one call's state in a BatchRun).
  struct BatchRun {
    bool point = false;                         // point-sampled views (else conservative)
    std::size_t most = 0;                       // fragments one packed k-buffer holds
    std::size_t take = 0, texels = 0;           // the views batched, their texels
    int largest = 0;                            // their largest side
    std::size_t host_entries = 0;               // triangles the host selected
    std::size_t invocations = 0;                // triangles the GPU selection considers
    bool gpu_sum = false;                       // offsets by the GPU's prefix sum
    std::size_t total = 0;                      // fragments counted
    std::uint32_t deepest = 0;                  // the deepest texel's count (host sum only)
    std::size_t selected = 0;                   // triangles the GPU selection kept
  };
  std::size_t plan_batch(const PeelJob* jobs, std::size_t count, BatchRun& run) const;
  void gather_batch(const PeelJob* jobs, PeelResult* outs, BatchRun& run);
  bool gather_batch_object(const PeelJob& job, std::size_t j, int slot, PeelResult& out, BatchRun& run);
  void put_view_record(const PeelJob& job, std::size_t base, bool point, PeelResult& out);
  void upload_batch_buffer(GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes,
                           std::size_t reserve, bool geometry);
  void upload_batch(const BatchRun& run);
  void select_batch(const BatchRun& run);
  void count_batch(BatchRun& run, Timings& t);
  void batch_offsets(BatchRun& run, Timings& t);
  void fill_batch(const BatchRun& run);
  void cover_batch_pass(const BatchRun& run, bool count_only);
  double resolve_batch_on_host(const PeelJob* jobs, PeelResult* outs, const BatchRun& run, Timings& t);
  // The GPU resolve of a drawn batch (batch.cpp): each job's PCS and layers.
  // False when a texel was deeper than the GPU resolve takes (the caller resolves on the host).
  bool resolve_batch_on_gpu(std::size_t take, std::size_t texels, bool point, PeelResult* outs, Timings& t);
  void dispatch_deep_rows(const DeepHeader& deep, std::size_t texels);
  // A conservative view resolved on the GPU is batched even alone (its deep texels split on the
  // GPU, the certified filter, GPU selection); other views need a second to batch with.
  bool batched_alone(const PeelJob& job) const { return job.conservative && !host_resolve(); }
  // Conservative views covered by the compute pass (GlOptions::coverage; auto: the cost models'
  // choice, the stage's own, `models`, where calibrate timed one; else compute on a GPU and
  // raster on a software renderer: docs/backends.md, "Which is chosen").
  const CostModels* models = nullptr;
  // Conservative views of at most `largest` texels a side covered by the compute pass. Not on a
  // software renderer beyond 255 texels a side: llvmpipe (and lavapipe under zink) ends a shader
  // invocation's loops after 65,535 iterations of all its loops together (gallivm's loop
  // limiter), and one invocation walks up to a view's texels (its own triangle's box, or its
  // share of its group's large boxes, shaders/conservative_cover.comp): such views rasterize
  // there, with the same fragments.
  static constexpr int kSoftwareComputeSide = 255;
  bool compute_coverage(int largest) const {
    if (software_renderer && largest > kSoftwareComputeSide) return false;
    if (options.coverage != Coverage::automatic) return options.coverage == Coverage::compute;
    if (models && !models->coverage.empty()) return models->coverage == "compute";
    return !software_renderer;
  }
  bool host_resolve() const {
    return options.resolve == Resolve::host || (options.resolve == Resolve::automatic && software_renderer);
  }
};

}  // namespace peelcd::gl
