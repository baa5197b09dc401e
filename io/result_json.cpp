#include "peelcd/io/result_json.h"

#include "peelcd/core/image/planner.h"
#include "peelcd/io/options_json.h"
#include "peelcd/version.h"

#include <cstring>

namespace peelcd {

namespace {
nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json score_json(const Score& s) {
  return {{"exact", s.exact}, {"found", s.found}, {"missed", s.missed}, {"miss_ratio", s.miss_ratio()},
          {"false_contacts", s.false_contacts}};
}
}  // namespace

nlohmann::json to_json(const FrameResult& r, const std::vector<Object>& objects, const DetectOptions& o,
                       const std::vector<Score>* check, const gl::GlOptions* gl) {
  using nlohmann::json;
  json pairs = json::array();
  std::size_t total = 0, colliding_objects = 0;
  Score sum;
  for (std::size_t i = 0; i < r.pairs.size(); ++i) {
    const PairResult& p = r.pairs[i];
    json colliding = json::array();
    for (const Contact& c : p.colliding) {
      colliding.push_back({{"tri_a", c.tri_a}, {"tri_b", c.tri_b}, {"kind", to_string(c.kind)}});
      if (c.classified()) colliding.back()["segment"] = {vec(c.p), vec(c.q)};  // none asked for (contacts: pairs)
    }
    total += p.colliding.size();
    colliding_objects += p.is_collision() ? 1 : 0;
    pairs.push_back({{"a", objects[p.object_a].name},
                     {"object_a", p.object_a},
                     {"object_b", p.object_b},
                     {"b", objects[p.object_b].name},
                     {"roi", {{"min", vec(p.roi.lo)}, {"max", vec(p.roi.hi)}}},
                     {"region", p.region.empty() ? nlohmann::json(nullptr)
                                                 : nlohmann::json{{"min", vec(p.region.lo)}, {"max", vec(p.region.hi)}}},
                     {"triangles_in_roi", {p.triangles_in_roi_a, p.triangles_in_roi_b}},
                     {"stage", p.exact_stage ? "exact" : std::strcmp(pair_path(p), "none") == 0 ? "none" : "image"},
                     {"path", pair_path(p)},
                     {"path_reason", pair_path_reason(p, o)},
                     {"views_exhaustive", p.views_exhaustive},
                     {"predicted_ms", {{"image", p.predicted_image_ms}, {"exact", p.predicted_exact_ms}}},
                     {"resolution", p.resolution},
                     {"epsilon", p.epsilon},
                     {"first_peeled", p.a_first ? "a" : "b"},
                     {"triangles_drawn", {p.triangles_drawn_a, p.triangles_drawn_b}},
                     {"layers", p.layers},
                     {"passes", p.passes},
                     {"pcs_count", p.pcs_count},
                     {"candidates", p.candidates},
                     {"colliding", colliding},
                     {"relation", to_string(p.relation)},
                     {"is_collision", p.is_collision()}});
    if (!p.relation_note.empty()) pairs.back()["relation_note"] = p.relation_note;
    if (o.margin > 0.0) {
      json near = json::array();
      for (const NearPair& n : p.near.pairs)
        near.push_back({{"tri_a", n.tri_a}, {"tri_b", n.tri_b}, {"distance", n.distance},
                        {"points", json::array({vec(n.p), vec(n.q)})}});
      pairs.back()["near"] = {{"margin", o.margin}, {"pairs", near}};
      if (p.near.within())
        pairs.back()["near"]["distance"] = p.near.distance, pairs.back()["near"]["witness"] = json::array({vec(p.near.p), vec(p.near.q)});
    }
    if (o.depth && p.object_a != p.object_b) {
      if (p.depth.known)
        pairs.back()["depth"] = {{"direction", vec(p.depth.direction)}, {"depth", p.depth.depth},
                                 {"bound", p.depth.bound}, {"directions", p.depth.directions},
                                 {"from", p.depth.source}};
      else
        pairs.back()["depth"] = {{"unknown", p.depth.reason}};
    }
    if (o.volume && p.object_a != p.object_b) {
      if (p.volume.known)
        pairs.back()["volume"] = {{"volume", p.volume.volume}, {"error", p.volume.error},
                                  {"gradient", vec(p.volume.gradient)}, {"resolution", p.volume.resolution},
                                  {"method", p.volume.method}};
      else
        pairs.back()["volume"] = {{"unknown", p.volume.reason}};
    }
    if (check) {
      const Score& s = check->at(i);
      pairs.back()["check"] = score_json(s);
      sum.exact += s.exact, sum.found += s.found, sum.missed += s.missed, sum.false_contacts += s.false_contacts;
    }
  }
  json out = {{"schema", kResultSchema},
          {"peelcd_version", PEELCD_VERSION_STRING},
          {"renderer", r.renderer},
          {"options", options_to_json(o)},
          {"pairs", pairs},
          {"colliding_pairs", total},
          {"colliding_objects", colliding_objects},
          {"gl_passes", r.gl_passes},
          {"gl_calls",
           {{"draws", r.gl_draws},
            {"dispatches", r.gl_dispatches},
            {"readbacks", r.gl_readbacks},
            {"bytes_uploaded", r.bytes_uploaded},
            {"geometry_bytes", r.geometry_bytes},
            {"bytes_read", r.bytes_read}}},
          {"rois_exact", r.rois_exact},
          {"views_exhaustive", r.views_exhaustive},
          {"gl_deep_texels", r.gl_deep_texels},
          {"views_host_resolved", r.views_host_resolved},
          {"gl_couples_apart", r.gl_couples_apart},
          {"timings_ms",
           {{"aabb", r.timings.aabb},
            {"upload", r.timings.upload},
            {"gpu", r.timings.gpu},
            {"readback", r.timings.readback},
            {"cpu", r.timings.cpu},
            {"total", r.timings.total},
            {"gl_wait", r.timings.gl_wait}}}};
  if (r.timings.gpu_timed) {
    out["timings_ms"]["gpu_raster"] = r.timings.gpu_raster;
    out["timings_ms"]["gpu_compute"] = r.timings.gpu_compute;
    out["timings_ms"]["gpu_transfer"] = r.timings.gpu_transfer;
    out["timings_ms"]["gpu_select"] = r.timings.gpu_select;
    out["timings_ms"]["gpu_cover"] = r.timings.gpu_cover;
    out["gpu_passes_untimed"] = r.timings.gpu_passes_untimed;
  }
  if (check) out["check"] = score_json(sum);
  if (gl) out["gl_options"] = gl_options_to_json(*gl);
  return out;
}

}  // namespace peelcd
