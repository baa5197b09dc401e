#pragma once
// The usual way to run peelcd on GL: a Detector (peelcd/core/image/detector.h) over a GlImageStage
// (peelcd/gl/gl_stage.h) on one context, in one object.
#include "peelcd/core/image/detector.h"
#include "peelcd/gl/gl_stage.h"

#include <memory>
#include <vector>

namespace peelcd::gl {

class Pipeline {
 public:
  // Shares ownership of `context` (it lives as long as the pipeline). Throws GlError.
  explicit Pipeline(std::shared_ptr<Context> context, GlOptions options = {});

  // See Detector::detect: std::invalid_argument on bad objects or options, GlError on a GL failure.
  FrameResult detect(const std::vector<Object>& objects, const DetectOptions& options) {
    return detector_.detect(objects, options);
  }
  void detect(const std::vector<Object>& objects, const DetectOptions& options, FrameResult& out) {
    detector_.detect(objects, options, out);
  }
  void capture_layers(std::vector<CapturedView>* sink) { detector_.capture_layers(sink); }

  const GlOptions& gl_options() const { return stage_->options(); }
  void set_gl_options(const GlOptions& options) { stage_->set_options(options); }
  const std::string& renderer() const { return stage_->renderer(); }
  const std::string& version() const { return stage_->version(); }
  int max_resolution() const { return stage_->max_resolution(); }

  GlImageStage& stage() { return *stage_; }
  Detector& detector() { return detector_; }

 private:
  std::shared_ptr<GlImageStage> stage_;
  Detector detector_;
};

}  // namespace peelcd::gl
