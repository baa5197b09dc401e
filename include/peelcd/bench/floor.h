#pragma once
// The floor under any image-space method on a GL context (peelcd bench): every ROI view a frame
// would peel (the same culling, tiles and triangles: Detector::for_each_view), its triangles
// uploaded and then drawn once with depth testing and a fragment shader that does nothing.
#include "peelcd/core/image/detector.h"
#include "peelcd/gl/gl_stage.h"

#include <vector>

namespace peelcd::bench {

// Milliseconds of those draws (to glFinish), excluding culling, gathering and upload. With
// `per_view`, also the milliseconds of each fused view summed over the ROIs (the first k of them
// are the floor of k views). `detector` must run on `stage`.
double floor_ms(Detector& detector, gl::GlImageStage& stage, const std::vector<Object>& objects,
                const DetectOptions& options, std::vector<double>* per_view = nullptr);

}  // namespace peelcd::bench
