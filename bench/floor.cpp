#include "peelcd/bench/floor.h"

#include <algorithm>

namespace peelcd::bench {

double floor_ms(Detector& detector, gl::GlImageStage& stage, const std::vector<Object>& objects,
                const DetectOptions& options, std::vector<double>* per_view) {
  if (per_view) per_view->assign(std::size_t(std::max(options.views, 0)), 0.0);
  double ms = 0.0;
  bool begun = false;
  struct End {
    gl::GlImageStage& stage;
    bool& begun;
    ~End() {
      if (begun) stage.end_frame();
    }
  } end{stage, begun};
  detector.for_each_view(objects, options, [&](const PeelJob& job) {
    if (!begun) {
      stage.begin_frame();
      begun = true;
    }
    const double t = stage.floor_draw_ms(job);
    ms += t;
    if (per_view && std::size_t(job.view_index) < per_view->size()) (*per_view)[std::size_t(job.view_index)] += t;
  });
  return ms;
}

}  // namespace peelcd::bench
