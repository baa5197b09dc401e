#pragma once
// OSMesa (software GL, llvmpipe): the deterministic reference backend. The context renders only
// into framebuffer objects; the 1x1 buffer exists because OSMesaMakeCurrent requires one.
#include "peelcd/gl/context.h"

#include <memory>

namespace peelcd::gl {

class OsmesaContext final : public Context {
 public:
  OsmesaContext();  // OpenGL 4.5 core; throws GlError
  ~OsmesaContext() override;
  void make_current() override;
  void restore_previous() noexcept override;
  ProcAddress proc_address(const char* name) override;
  std::string backend() const override { return "osmesa"; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peelcd::gl
