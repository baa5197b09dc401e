#include "gl_osmesa/osmesa_context.h"

#include <GL/osmesa.h>

namespace peelcd::gl {

struct OsmesaContext::Impl {
  OSMesaContext ctx = nullptr;
  unsigned char pixel[4] = {0, 0, 0, 0};
};

OsmesaContext::OsmesaContext() : impl_(std::make_unique<Impl>()) {
  const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA,
                         OSMESA_DEPTH_BITS, 0,
                         OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION, 4,
                         OSMESA_CONTEXT_MINOR_VERSION, 5,
                         0};
  impl_->ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!impl_->ctx)
    throw GlError("peelcd::gl::OsmesaContext: cannot create an OpenGL 4.5 core context "
                  "(is libosmesa6 installed, with llvmpipe?)");
  make_current();
}

OsmesaContext::~OsmesaContext() {
  if (impl_->ctx) OSMesaDestroyContext(impl_->ctx);
}

void OsmesaContext::make_current() {
  if (!OSMesaMakeCurrent(impl_->ctx, impl_->pixel, GL_UNSIGNED_BYTE, 1, 1))
    throw GlError("peelcd::gl::OsmesaContext: OSMesaMakeCurrent failed");
}

ProcAddress OsmesaContext::proc_address(const char* name) {
  return reinterpret_cast<ProcAddress>(OSMesaGetProcAddress(name));
}

}  // namespace peelcd::gl
