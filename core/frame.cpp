#include "peelcd/core/frame.h"

#include <cstdio>

#include "peelcd/core/planner.h"
#include "peelcd/core/view.h"

#include <algorithm>
#include <cmath>
#include <map>
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



const char* pair_path(const PairResult& p) {
  if (p.exact_stage) return "exact";
  if (p.views_peeled == 0) return "none";
  if (p.views_exhaustive == 0) return "image";
  return p.views_exhaustive == p.views_peeled ? "exhaustive" : "image+exhaustive";
}

std::string pair_path_reason(const PairResult& p, const DetectOptions& o) {
  char buf[320];
  if (p.exact_stage) {
    if (o.stage == Stage::exact) return "--stage exact";
    if (p.margin_fallback) {
      std::snprintf(buf, sizeof buf,
                    "the margin %g is wider than %g of the ROI's longest side (or its view leaves the float range): "
                    "the image stage would grow every triangle over much of the view; tested on the exact CPU path",
                    o.margin, kImageMarginShare);
      return buf;
    }
    if (p.object_a == p.object_b) {
      std::snprintf(buf, sizeof buf,
                    "a self pair: the exact CPU path under --stage auto (predicted at %.3f ms by its candidate couples)",
                    p.predicted_exact_ms);
      return buf;
    }
    std::snprintf(buf, sizeof buf, "routed: the exact CPU path was predicted at %.3f ms, the image stage at %.3f ms",
                  p.predicted_exact_ms, p.predicted_image_ms);
    return buf;
  }
  if (p.views_peeled == 0) return "contact culling kept no triangle of one object: no contact possible";
  const std::string why = o.stage == Stage::image ? std::string("--stage image") : [&] {
    std::snprintf(buf, sizeof buf, "routed: the image stage was predicted at %.3f ms, the exact CPU path at %.3f ms",
                  p.predicted_image_ms, p.predicted_exact_ms);
    return std::string(buf);
  }();
  if (p.views_exhaustive == 0) return why;
  std::snprintf(buf, sizeof buf,
                "; %d of %d views too deep or too large (%dx%d) for the image stage's k-buffer: their triangles' "
                "box-overlapping couples were tested exactly instead (no layers, no PCS)",
                p.views_exhaustive, p.views_peeled, p.resolution, p.resolution);
  return why + buf;
}

}  // namespace peelcd

namespace peelcd {

void relate_pairs(std::vector<PairResult>& pairs, const std::function<const Mesh&(std::size_t)>& mesh_of,
                  const std::vector<Aabb>& boxes, const DetectOptions& options, const std::vector<char>* near_found) {
  const int n = options.resolution > 0 ? options.resolution : kVolumeResolution;
  // The margin's trees, one per object, built on its first pair (none without a margin).
  std::map<std::size_t, Bvh> trees;
  const auto tree_of = [&](std::size_t id) -> const Bvh& {
    auto it = trees.find(id);
    if (it == trees.end()) {
      it = trees.emplace(id, Bvh{}).first;
      it->second.build(mesh_of(id).vertices, mesh_of(id).triangles);
    }
    return it->second;
  };
  for (std::size_t pi = 0; pi < pairs.size(); ++pi) {
    PairResult& p = pairs[pi];
    const bool found = near_found && (*near_found)[pi];
    p.relation_note.clear();
    p.volume = VolumeEstimate{};
    p.depth = PenetrationDepth{};
    if (!found) p.near = Proximity{};
    // max_contacts: a pair's lanes may each have stopped at N; the first N, sorted, are kept.
    const bool capped = options.max_contacts && p.colliding.size() >= options.max_contacts;
    if (capped) p.colliding.resize(options.max_contacts);
    const auto note_cap = [&] {
      if (capped)
        p.relation_note = "max_contacts " + std::to_string(options.max_contacts) +
                          ": the relation is from the contacts found before the tests stopped";
    };
    if (p.object_a == p.object_b) {  // self: from the contacts alone
      p.relation = contact_relation(p.colliding);
      note_cap();
      if (options.margin > 0.0) {
        std::vector<std::uint32_t> rep;
        vertex_representatives(mesh_of(p.object_a), options.self_adjacency, rep);
        p.near = near_self_pairs(mesh_of(p.object_a), tree_of(p.object_a), rep, options.margin);
      }
      continue;
    }
    if (options.margin > 0.0 && !found)
      p.near = near_pairs(mesh_of(p.object_a), mesh_of(p.object_b), tree_of(p.object_b), options.margin);
    const Aabb& ba = boxes[p.object_a];
    const Aabb& bb = boxes[p.object_b];
    const bool within = !ba.empty() && !bb.empty() &&
                        (((ba.lo.array() >= bb.lo.array()).all() && (ba.hi.array() <= bb.hi.array()).all()) ||
                         ((bb.lo.array() >= ba.lo.array()).all() && (bb.hi.array() <= ba.hi.array()).all()));
    if (!p.colliding.empty() || !within) {  // from the contacts: no mesh read
      p.relation = contact_relation(p.colliding);
      note_cap();
      // Touching only, one box within the other: touching from inside is containment.
      if (p.relation == Relation::touching && within && !capped)
        p.relation = touching_relation(mesh_of(p.object_a), mesh_of(p.object_b), ba, bb, p.colliding, p.relation_note);
    } else {
      p.relation = relate(mesh_of(p.object_a), mesh_of(p.object_b), ba, bb, p.colliding, p.relation_note);
    }
    if (options.depth) {
      if (colliding_relation(p.relation))
        p.depth = penetration_depth(mesh_of(p.object_a), mesh_of(p.object_b), p.colliding);
      else
        p.depth.reason = p.relation == Relation::unknown ? "the relation is unknown: " + p.relation_note
                                                         : std::string("the objects do not collide");
    }
    if (options.volume) {
      if (p.relation == Relation::disjoint) {  // no overlap: nothing to integrate, 0 if both are closed
        p.volume = overlap_volume(mesh_of(p.object_a), mesh_of(p.object_b), Aabb{}, n);
      } else {
        p.volume = overlap_volume(mesh_of(p.object_a), mesh_of(p.object_b), p.roi, n);
      }
    }
  }
}

void FrameResult::reset_counters() {
  timings = Timings{};
  gl_passes = rois_peeled = triangles_uploaded = triangles_indexed = shape_uploads = 0;
  pcs_readbacks = views_exhaustive = rois_exact = 0;
  gl_draws = gl_dispatches = gl_readbacks = bytes_uploaded = bytes_read = geometry_bytes = 0;
  gl_deep_texels = views_host_resolved = 0;
}

void FrameResult::add_image_work(const FrameResult& o) {
  gl_passes += o.gl_passes;
  rois_peeled += o.rois_peeled;
  triangles_uploaded += o.triangles_uploaded;
  pcs_readbacks += o.pcs_readbacks;
  views_exhaustive += o.views_exhaustive;
  gl_draws += o.gl_draws;
  gl_dispatches += o.gl_dispatches;
  gl_readbacks += o.gl_readbacks;
  bytes_uploaded += o.bytes_uploaded;
  bytes_read += o.bytes_read;
  geometry_bytes += o.geometry_bytes;
  gl_deep_texels += o.gl_deep_texels;
  views_host_resolved += o.views_host_resolved;
  timings.upload += o.timings.upload;
  timings.gpu += o.timings.gpu;
  timings.readback += o.timings.readback;
  timings.cpu += o.timings.cpu;
  timings.gl_wait += o.timings.gl_wait;
  timings.gpu_raster += o.timings.gpu_raster;
  timings.gpu_compute += o.timings.gpu_compute;
  timings.gpu_transfer += o.timings.gpu_transfer;
  timings.gpu_timed = timings.gpu_timed || o.timings.gpu_timed;
  timings.gpu_passes_untimed += o.timings.gpu_passes_untimed;
}

}  // namespace peelcd
