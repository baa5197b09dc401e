#include "peelcd/gl_osmesa/osmesa_context.h"

#include <GL/osmesa.h>

namespace peelcd::gl {

struct OsmesaContext::Impl {
  OSMesaContext ctx = nullptr;
  unsigned char pixel[4] = {0, 0, 0, 0};
  // The caller's context, current before make_current(), and its colour buffer.
  OSMesaContext prev = nullptr;
  GLint prev_width = 0, prev_height = 0, prev_format = 0;
  void* prev_buffer = nullptr;
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
  // Made current once to prove it works, then the caller's context (if any) is current again.
  make_current();
  restore_previous();
}

OsmesaContext::~OsmesaContext() {
  if (bound_context.context == this) bound_context = {};
  if (impl_->ctx) OSMesaDestroyContext(impl_->ctx);
}

void OsmesaContext::make_current() {
  // Another platform's peelcd context bound since: OSMesaGetCurrentContext() would read that
  // one (Mesa's one GL dispatch) as an OSMesa context; there is no OSMesa context to give back.
  const bool foreign = bound_context.platform == ContextPlatform::egl;
  const OSMesaContext current = foreign ? nullptr : OSMesaGetCurrentContext();
  impl_->prev = nullptr;
  if (current == impl_->ctx) {  // already current: nothing to switch or give back
    bound_context = {this, ContextPlatform::osmesa};
    return;
  }
  if (current && OSMesaGetColorBuffer(current, &impl_->prev_width, &impl_->prev_height, &impl_->prev_format,
                                      &impl_->prev_buffer))
    impl_->prev = current;
  if (!OSMesaMakeCurrent(impl_->ctx, impl_->pixel, GL_UNSIGNED_BYTE, 1, 1)) {
    impl_->prev = nullptr;
    throw GlError("peelcd::gl::OsmesaContext: OSMesaMakeCurrent failed");
  }
  bound_context = {this, ContextPlatform::osmesa};
}

// The caller's buffer is given back as GL_UNSIGNED_BYTE (the common case; OSMesa does not tell
// the type a buffer was bound with).
void OsmesaContext::restore_previous() noexcept {
  if (!impl_->prev) return;
  OSMesaMakeCurrent(impl_->prev, impl_->prev_buffer, GL_UNSIGNED_BYTE, impl_->prev_width, impl_->prev_height);
  impl_->prev = nullptr;
  bound_context = {};
}

ProcAddress OsmesaContext::proc_address(const char* name) {
  return reinterpret_cast<ProcAddress>(OSMesaGetProcAddress(name));
}

}  // namespace peelcd::gl
