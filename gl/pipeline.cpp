#include "peelcd/gl/pipeline.h"

namespace peelcd::gl {

Pipeline::Pipeline(std::shared_ptr<Context> context, GlOptions options)
    : stage_(std::make_shared<GlImageStage>(std::move(context), options)), detector_(stage_) {}

}  // namespace peelcd::gl
