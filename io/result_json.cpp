#include "peelcd/io/result_json.h"

#include "peelcd/io/options_json.h"
#include "peelcd/version.h"

namespace peelcd {

namespace {
nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

nlohmann::json to_json(const FrameResult& r, const std::vector<Object>& objects, const DetectOptions& o) {
  using nlohmann::json;
  json pairs = json::array();
  std::size_t total = 0;
  for (const PairResult& p : r.pairs) {
    json colliding = json::array(), segments = json::array(), kinds = json::array();
    for (const Contact& c : p.colliding) {
      colliding.push_back({c.tri_a, c.tri_b});
      segments.push_back({vec(c.p), vec(c.q)});
      kinds.push_back(to_string(c.kind));
    }
    total += p.colliding.size();
    pairs.push_back({{"a", objects[p.object_a].name},
                     {"b", objects[p.object_b].name},
                     {"roi", {{"min", vec(p.roi.lo)}, {"max", vec(p.roi.hi)}}},
                     {"region", p.region.empty() ? nlohmann::json(nullptr)
                                                 : nlohmann::json{{"min", vec(p.region.lo)}, {"max", vec(p.region.hi)}}},
                     {"triangles_in_roi", {p.triangles_in_roi_a, p.triangles_in_roi_b}},
                     {"stage", p.exact_stage ? "exact" : "image"},
                     {"predicted_ms", {{"image", p.predicted_image_ms}, {"exact", p.predicted_exact_ms}}},
                     {"resolution", p.resolution},
                     {"epsilon", p.epsilon},
                     {"first_peeled", p.a_first ? "a" : "b"},
                     {"triangles_drawn", {p.triangles_drawn_a, p.triangles_drawn_b}},
                     {"layers", p.layers},
                     {"passes", p.passes},
                     {"pcs", p.pcs_count},
                     {"candidates", p.candidates},
                     {"colliding", colliding},
                     {"segments", segments},
                     {"kinds", kinds}});
  }
  return {{"peelcd_version", PEELCD_VERSION_STRING},
          {"renderer", r.renderer},
          {"options", options_to_json(o)},
          {"pairs", pairs},
          {"colliding_pairs", total},
          {"gl_passes", r.gl_passes},
          {"rois_exact", r.rois_exact},
          {"timings_ms",
           {{"aabb", r.timings.aabb},
            {"upload", r.timings.upload},
            {"gpu", r.timings.gpu},
            {"readback", r.timings.readback},
            {"cpu", r.timings.cpu},
            {"total", r.timings.total}}}};
}

}  // namespace peelcd
