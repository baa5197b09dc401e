#include "peelcd/io/options_json.h"

namespace peelcd {

nlohmann::json options_to_json(const DetectOptions& o) {
  return {{"conservative", o.conservative}, {"theta", o.theta},   {"phi", o.phi}, {"roll", o.roll},         {"resolution", o.resolution},     {"budget", o.budget},
          {"ids", to_string(o.ids)}, {"epsilon", o.epsilon}, {"peel", to_string(o.peel)}, {"slope", o.slope},
          {"views", o.views},   {"cull", to_string(o.cull)}, {"edge_texels", edge_texels_of(o)}, {"stage", to_string(o.stage)}};
}

nlohmann::json gl_options_to_json(const gl::GlOptions& o) {
  return {{"peeler", to_string(o.peeler)}, {"resolve", to_string(o.resolve)}};
}

}  // namespace peelcd
