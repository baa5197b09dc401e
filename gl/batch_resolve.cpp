// The resolve of a batch of views (batch.cpp): the counts read back, the host resolve of the
// packed k-buffer (core/image/kbuffer.cpp), or the GPU resolve (shaders/conservative_batch_resolve.comp,
// shaders/abuffer_resolve.comp with PEELCD_BATCH) with its deep texels' rows.
#include "stage_impl.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace peelcd::gl {

// The host resolve of a filled batch: the selection's entries' IDs read back (by draw order),
// the packed k-buffer mapped, each view's part resolved (core/image/kbuffer.cpp). Returns the
// milliseconds the map took (readback, not GPU time).
double GlImageStage::Impl::resolve_batch_on_host(const PeelJob* jobs, PeelResult* outs, const BatchRun& run,
                                                 Timings& t) {
  if (run.selected) {
    const auto t_entries = Clock::now();
    batch.entry_data.resize(run.host_entries + run.selected);
    read_buffer(batch.entries, GLintptr(run.host_entries * kBatchEntryBytes), GLsizeiptr(run.selected * kBatchEntryBytes),
                batch.entry_data.data() + run.host_entries);
    t.readback += ms_since(t_entries);
    for (std::size_t k = run.host_entries; k < batch.entry_data.size(); ++k) batch.ids.push_back(batch.entry_data[k][2]);
  }
  const auto t_map = Clock::now();
  const auto* fragments =
      static_cast<const KFragment*>(map_for_reading(fragment_buffer, run.total * sizeof(KFragment)));
  const double map_ms = ms_since(t_map);
  t.readback += map_ms;
  if (!fragments && run.total) {
    check("mapping the packed k-buffer");
    throw GlError("peelcd::gl::GlImageStage: mapping the packed k-buffer failed");
  }
  std::size_t base = 0;
  for (std::size_t j = 0; j < run.take; ++j) {
    const PeelJob& job = jobs[j];
    PeelResult& out = outs[j];
    const int n = job.view.resolution;
    KBuffer kb;
    kb.counts = batch.counts.data() + base;
    kb.fragments = fragments;
    kb.offsets = batch.offsets.data() + base;
    kb.resolution = n;
    kb.slots = run.deepest;
    KResolveParams p;
    p.conservative = !run.point;
    p.epsilon_window = out.epsilon_window;
    p.slope = out.slope;
    p.full_peel = job.peel == PeelMode::full;
    p.first_object = std::uint32_t(job.first);
    p.ids[0] = batch.ids.data();  // keys hold the draw order of the whole batch
    p.ids[1] = batch.ids.data();
    const KResolveResult got = resolver.resolve(kb, p, out.pcs, job.capture ? &out.captured : nullptr);
    out.layers = int(got.max_layers);
    out.peel_passes = 1;
    if (!out.pcs.empty()) ++out.pcs_readbacks;
    base += std::size_t(n) * std::size_t(n);
  }
  if (fragments) gl.UnmapNamedBuffer(fragment_buffer);
  check("the host resolve of the packed k-buffer");
  return map_ms;
}

// The count pass's counts read back into batch.counts, their prefix sums into batch.offsets (the
// host resolve's; uploaded by the caller for the fill pass), the deepest texel's count into
// batch.deepest; returns the total.
std::size_t GlImageStage::Impl::read_batch_counts(std::size_t texels, Timings& t) {
  const auto t_counts = Clock::now();
  batch.counts.resize(texels);
  read_buffer(count_buffer, 0, GLsizeiptr(texels * 4), batch.counts.data());
  t.readback += ms_since(t_counts);
  batch.offsets.resize(texels);
  std::size_t total = 0;
  batch.deepest = 0;
  for (std::size_t k = 0; k < texels; ++k) {
    batch.offsets[k] = std::uint32_t(std::min<std::size_t>(total, 0xffffffffu));
    total += batch.counts[k];
    batch.deepest = std::max(batch.deepest, batch.counts[k]);
  }
  return total;
}

// The deep texels' rows (shaders/conservative_batch_resolve.comp with PEELCD_DEEP): a work group
// per row and block of fragments, rows in dispatches of at most 65535 work groups wide.
void GlImageStage::Impl::dispatch_deep_rows(const DeepHeader& deep, std::size_t texels) {
  const int filter = options.gpu_filter ? 1 : 0;
  gl.UseProgram(cons_deep[filter].id);
  gl.Uniform1ui(cons_deep[filter].texels, GLuint(texels));
  for (std::size_t base = 0; base < deep.row_count; base += 65535) {
    gl.Uniform1ui(cons_deep[filter].row_base, GLuint(base));
    dispatch(GLuint(std::min<std::size_t>(deep.row_count - base, 65535)), deep.max_blocks, 1);
  }
  barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  gl.UseProgram(cons_batch_resolve[filter].id);
}

bool GlImageStage::Impl::resolve_batch_on_gpu(std::size_t take, std::size_t texels, bool point, PeelResult* outs,
                                              Timings& t) {
  // Per-view depths, zeroed; the PCS header reset; one dispatch over every texel.
  const std::size_t layer_bytes = take * sizeof(std::uint32_t);
  if (layer_bytes > batch.layers_capacity) {
    batch.layers_capacity = std::max(layer_bytes, batch.layers_capacity * 3 / 2);
    gl.NamedBufferData(batch.layers, GLsizeiptr(batch.layers_capacity), nullptr, GL_DYNAMIC_READ);
  }
  clear_buffer(batch.layers, GLsizeiptr(layer_bytes));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, batch.entries);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, batch.layers);
  gl.BindTextureUnit(0, count_tex);
  gl.BindTextureUnit(1, fragment_tex);
  // Conservative: the program with the certified filter unless GlOptions::gpu_filter is off.
  const BatchResolveProgram& program = point ? point_batch_resolve : cons_batch_resolve[options.gpu_filter ? 1 : 0];
  gl.UseProgram(program.id);
  gl.Uniform1ui(program.texels, GLuint(texels));
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, batch.offset_buffer);
  if (!point && batch.deep_rows_capacity == 0) {
    batch.deep_rows_capacity = 4096;
    gl.NamedBufferData(batch.deep_rows, GLsizeiptr(sizeof(DeepHeader) + batch.deep_rows_capacity * 8), nullptr, GL_DYNAMIC_COPY);
  }
  // The certified filter reads the views (3), the resident (7) and the frame's corners (8) where
  // the draw bound them.
  if (!point) gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 15, batch.deep_rows);
  BatchPcsHeader got{};
  DeepHeader deep{};
  // The list's pairs are 16 bytes here (IDs and view), after a 32-byte header: half as many fit,
  // less one.
  const auto fitting = [&] { return std::uint32_t(pcs_capacity / 2 - 1); };
  for (;;) {
    const BatchPcsHeader header{0, fitting(), 0, 0, 0, {0, 0, 0}};
    upload_buffer(pcs_buffer, 0, sizeof header, &header);
    if (!point) {
      const DeepHeader empty{0, std::uint32_t(batch.deep_rows_capacity), 0, 0};
      upload_buffer(batch.deep_rows, 0, sizeof empty, &empty);
    }
    dispatch(GLuint((texels + 63) / 64), 1, 1);
    barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    const auto t_read = Clock::now();
    read_buffer(pcs_buffer, 0, sizeof got, &got);
    t.readback += ms_since(t_read);
    if (got.max_fragments) return false;  // a texel deeper than this resolve takes
    // Conservative: texels deeper than PEELCD_GPU_RESOLVE_DEPTH left rows for the second program
    // (the deepest texel's count, max_layers, says whether any did: no read otherwise).
    if (!point && got.max_layers > PEELCD_GPU_RESOLVE_DEPTH) {
      const auto t_deep = Clock::now();
      read_buffer(batch.deep_rows, 0, sizeof deep, &deep);
      t.readback += ms_since(t_deep);
      if (deep.row_count > batch.deep_rows_capacity) {  // larger, and the dispatch again
        batch.deep_rows_capacity = std::size_t(deep.row_count) * 3 / 2;
        gl.NamedBufferData(batch.deep_rows, GLsizeiptr(sizeof(DeepHeader) + batch.deep_rows_capacity * 8), nullptr,
                           GL_DYNAMIC_COPY);
        gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 15, batch.deep_rows);
        continue;
      }
      dispatch_deep_rows(deep, texels);
      const auto t_again = Clock::now();
      read_buffer(pcs_buffer, 0, sizeof got, &got);
      t.readback += ms_since(t_again);
    }
    if (got.count <= fitting()) break;
    grow_pcs(2 * (got.count + got.count / 2));  // the list did not fit: larger, and the dispatch again
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, pcs_buffer);
  }
  counters->deep_texels += deep.deep_texels;
  counters->couples_apart += got.couples_apart;
  const auto t_read = Clock::now();
  batch.view_layers.resize(take);
  read_buffer(batch.layers, 0, GLsizeiptr(layer_bytes), batch.view_layers.data());
  batch.pairs.resize(std::size_t(got.count) * 4);
  if (got.count) {
    read_buffer(pcs_buffer, sizeof(BatchPcsHeader), GLsizeiptr(got.count) * 16, batch.pairs.data());
  }
  t.readback += ms_since(t_read);
  check("the GPU resolve of the packed k-buffer");
  for (std::size_t k = 0; k < got.count; ++k)  // ID of A's, ID of B's, the view
    outs[batch.pairs[4 * k + 2]].pcs.push_back(IdPair{batch.pairs[4 * k], batch.pairs[4 * k + 1]});
  for (std::size_t j = 0; j < take; ++j) {
    PeelResult& out = outs[j];
    out.layers = int(batch.view_layers[j]);
    out.peel_passes = 1;
    if (!out.pcs.empty()) ++out.pcs_readbacks;
  }
  return true;
}

}  // namespace peelcd::gl
