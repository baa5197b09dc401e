#pragma once
// The dump viewer: one self-contained HTML page (images inline, no network) showing every ROI
// view's layers side by side in peel order, the PCS texels marked, and the colliding pairs.
#include "peelcd/oracle/dump.h"

#include <string>

namespace peelcd::oracle {

std::string viewer_html(const Dump& dump);

}  // namespace peelcd::oracle
