#pragma once
// The dump viewer: one self-contained HTML page (images inline, no network) showing every ROI
// view's layers side by side in peel order, the PCS texels marked, and the colliding pairs.
#include "peelcd/oracle/dump.h"

#include <cstdint>
#include <string>
#include <vector>

namespace peelcd::oracle {

std::string viewer_html(const Dump& dump);
// Whether the page holds the layers' texel words itself (a dump up to 24 MB of them); if not,
// each layer's are a script beside its preview, <view dir>/layerKK.js, written by write_dump()
// from viewer_layer_script() (view_index: the view's place over all pairs, in order).
bool viewer_embeds_layers(const Dump& dump);
// Base64 of bytes, and of a layer's words (little-endian), as the pages embed them.
std::string base64_bytes(const std::vector<std::uint8_t>& bytes);
std::string layer_base64(const std::vector<std::uint32_t>& layer);
std::string viewer_layer_script(std::size_t view_index, std::size_t k, const std::vector<std::uint32_t>& layer);

}  // namespace peelcd::oracle
