#pragma once
// The benchmark of `peelcd bench`: peelcd's configurations and its peers side by side on the
// same frames, medians per frame after an untimed pass, miss ratios against the exact pairs.
//
// Rows: peelcd's persistent bodies (peelcd::World: the default, and its image stage), the frame
// API's configurations (stage router, exact CPU path, image stage with its variants, point
// sampling, the paper's configuration), CGAL cropped to the overlap box (the exact reference),
// FCL 0.7 with trees kept (rigid) and refitted or rebuilt (deforming), and the floors (one bare
// draw of the triangles a configuration would draw). `short_rows` keeps the World rows, the
// frame API's router and image stage, the peers and the floors (the scale scenes).
#include "peelcd/bench/peers.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exact/reference.h"

#include <functional>
#include <optional>
#include <memory>
#include <string>
#include <vector>

namespace peelcd::bench {

struct Suite {
  std::string scene;  // its name in the table's title
  std::size_t frames = 0;
  int phases = 1;
  std::function<int(std::size_t)> phase;  // frame -> phase (0 .. phases - 1); empty: 0
  // Frame f's objects into `objects` (storage reused). A scene file's objects are the same each
  // frame.
  std::function<void(std::size_t, std::vector<Object>&)> frame;
  int res = 0;            // 0: the shared 512^2 budget with tiles by need (detect's default)
  unsigned threads = 1;   // every method's threads
  // > 0: the default World row again with this many threads, timed side by side with the
  // others (its ratio to the default row, same frames, printed under the table).
  unsigned scaling_threads = 0;
  // The World rows' World::time_routes() (unset: timed on a GPU, not on a software renderer).
  std::optional<bool> time_routes;
  bool short_rows = false;
  // Rows of FCL, Embree and Bullet each set up as a plain user writes it (PlainPeer), and each
  // peer row's ratio to its library's printed under the table (docs/performance.md, "The peers").
  bool audit = false;
  // The image stage's GPU passes timed by GL timer queries (the image-work table's raster,
  // compute and transfer columns) in every peelcd row's frames.
  bool gpu_timers = true;
  // Freed memory stays in the process while the suite runs (glibc: mallopt), so that one
  // method's frees do not slow the next method's frame; false leaves the allocator as it is.
  bool keep_freed_memory = true;
  std::shared_ptr<ImageStage> stage;  // a GL stage (peelcd/backends.h): the floors draw on it
  std::function<void(std::size_t, std::size_t)> progress;  // (frames done, frames)
};

// Runs the suite, prints its tables on stdout, returns the CSV (one row per frame and method:
// peelcd_version,frame,method,ms,nctp,found,false_contacts). Throws std::invalid_argument when
// the stage is not a GL stage or `res` is above its largest view.
std::string run_suite(const Suite& suite);

double median(std::vector<double> values);
// Found, missed and false contacts of a peelcd frame against the exact pairs of the CGAL peer.
Score score_frame(const FrameResult& result, const PeerFrame& exact);

}  // namespace peelcd::bench
