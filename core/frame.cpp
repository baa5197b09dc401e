#include "peelcd/core/frame.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace peelcd {

const char* to_string(PeelMode mode) { return mode == PeelMode::full ? "full" : "alternate"; }

std::optional<PeelMode> parse_peel_mode(const std::string& text) {
  if (text == "full") return PeelMode::full;
  if (text == "alternate" || text == "paper") return PeelMode::alternate;
  return std::nullopt;
}


const char* to_string(Cull cull) { return cull == Cull::contact ? "contact" : "box"; }

std::optional<Cull> parse_cull(const std::string& text) {
  if (text == "contact") return Cull::contact;
  if (text == "box" || text == "none") return Cull::box;
  return std::nullopt;
}

const char* to_string(Stage stage) {
  switch (stage) {
    case Stage::image: return "image";
    case Stage::exact: return "exact";
    case Stage::automatic: break;
  }
  return "auto";
}

std::optional<Stage> parse_stage(const std::string& text) {
  if (text == "image") return Stage::image;
  if (text == "exact") return Stage::exact;
  if (text == "auto" || text == "automatic") return Stage::automatic;
  return std::nullopt;
}





const char* to_string(Relation r) {
  switch (r) {
    case Relation::disjoint: return "disjoint";
    case Relation::touching: return "touching";
    case Relation::crossing: return "crossing";
    case Relation::a_inside_b: return "a_inside_b";
    case Relation::b_inside_a: return "b_inside_a";
    case Relation::unknown: return "unknown";
  }
  return "unknown";
}

const char* to_string(IdMode mode) {
  switch (mode) {
    case IdMode::unique: return "unique";
    case IdMode::paper: return "paper";
    case IdMode::ring: return "ring";
  }
  return "?";
}

std::optional<IdMode> parse_id_mode(const std::string& text) {
  if (text == "unique") return IdMode::unique;
  if (text == "paper") return IdMode::paper;
  if (text == "ring") return IdMode::ring;
  return std::nullopt;
}

const char* to_string(SelfAdjacency adjacency) { return adjacency == SelfAdjacency::index ? "index" : "position"; }

std::optional<SelfAdjacency> parse_self_adjacency(const std::string& text) {
  if (text == "index") return SelfAdjacency::index;
  if (text == "position") return SelfAdjacency::position;
  return std::nullopt;
}

const char* to_string(ContactDetail detail) { return detail == ContactDetail::segments ? "segments" : "pairs"; }

std::optional<ContactDetail> parse_contact_detail(const std::string& text) {
  if (text == "segments") return ContactDetail::segments;
  if (text == "pairs") return ContactDetail::pairs;
  return std::nullopt;
}

double edge_texels_of(const DetectOptions& o) {
  if (o.edge_texels) return *o.edge_texels;
  return o.conservative ? kConservativeEdgeTexels : kPointEdgeTexels;
}

DetectOptions paper_options() {
  DetectOptions o;
  o.conservative = false;
  o.theta = o.phi = o.roll = 0.0;
  o.ids = IdMode::paper;
  o.peel = PeelMode::alternate;
  o.slope = 0.0;
  o.views = 1;
  o.cull = Cull::box;
  o.edge_texels = 0.0;
  o.stage = Stage::image;
  return o;
}






void FrameResult::reset_counters() {
  timings = Timings{};
  gl_passes = rois_peeled = triangles_uploaded = triangles_indexed = shape_uploads = 0;
  pcs_readbacks = views_exhaustive = rois_exact = 0;
  gl_draws = gl_dispatches = gl_readbacks = bytes_uploaded = bytes_read = geometry_bytes = 0;
  gl_deep_texels = views_host_resolved = gl_couples_apart = 0;
}

void FrameResult::add_image_work(const FrameResult& o) {
  gl_passes += o.gl_passes;
  rois_peeled += o.rois_peeled;
  triangles_uploaded += o.triangles_uploaded;
  triangles_indexed += o.triangles_indexed;
  shape_uploads += o.shape_uploads;
  pcs_readbacks += o.pcs_readbacks;
  views_exhaustive += o.views_exhaustive;
  gl_draws += o.gl_draws;
  gl_dispatches += o.gl_dispatches;
  gl_readbacks += o.gl_readbacks;
  bytes_uploaded += o.bytes_uploaded;
  bytes_read += o.bytes_read;
  geometry_bytes += o.geometry_bytes;
  gl_deep_texels += o.gl_deep_texels;
  gl_couples_apart += o.gl_couples_apart;
  views_host_resolved += o.views_host_resolved;
  timings.aabb += o.timings.aabb;
  timings.upload += o.timings.upload;
  timings.gpu += o.timings.gpu;
  timings.readback += o.timings.readback;
  timings.cpu += o.timings.cpu;
  timings.gl_wait += o.timings.gl_wait;
  timings.gpu_raster += o.timings.gpu_raster;
  timings.gpu_compute += o.timings.gpu_compute;
  timings.gpu_transfer += o.timings.gpu_transfer;
  timings.gpu_select += o.timings.gpu_select;
  timings.gpu_cover += o.timings.gpu_cover;
  timings.gpu_timed = timings.gpu_timed || o.timings.gpu_timed;
  timings.gpu_passes_untimed += o.timings.gpu_passes_untimed;
}

}  // namespace peelcd
