// GL resources of the stage, grown as views need them and reused across views and frames.
#include "stage_impl.h"

#include <algorithm>

namespace peelcd::gl {

void GlImageStage::Impl::grow_pcs(std::uint32_t capacity) {
  pcs_capacity = capacity;
  gl.NamedBufferData(pcs_buffer, sizeof(PcsHeader) + std::size_t(capacity) * 8, nullptr, GL_DYNAMIC_READ);
}

// The most fragments per texel a k-buffer of `texels` texels can hold: 16 bytes each, within
// the largest shader storage block and the largest buffer texture (whose texel index is a
// 32-bit signed integer in the shaders).
std::size_t GlImageStage::Impl::fitting_slots(std::size_t texels) const {
  return std::min(max_storage_block / 16, fetchable()) / std::max<std::size_t>(texels, 1);
}

// Texels a shader can fetch from a buffer texture: GL_MAX_TEXTURE_BUFFER_SIZE, and the
// shaders' index is a 32-bit signed integer.
std::size_t GlImageStage::Impl::fetchable() const {
  return std::min<std::size_t>(std::size_t(std::max(max_texture_buffer, 0)), 0x7fffffff);
}

// The k-buffer for `texels` texels with `view_slots` fragments each: 4 bytes of count per
// texel, 16 bytes per fragment. Grows only (steady state allocates nothing), and always to
// the largest tile seen so far with the most slots asked for (within the largest storage
// block): the tile changes with the number of ROIs from frame to frame, and a small deep tile
// followed by a large one would otherwise grow it twice.
void GlImageStage::Impl::ensure_kbuffer(std::size_t texels, std::size_t view_slots) {
  if (texels > kbuffer_texels) {
    gl.NamedBufferData(count_buffer, GLsizeiptr(texels * 4), nullptr, GL_DYNAMIC_COPY);
    kbuffer_texels = texels;
    gl.TextureBuffer(count_tex, GL_R32UI, count_buffer);
  }
  const std::size_t most = std::min(max_storage_block / 16, fetchable());
  const std::size_t wanted = std::max(texels * view_slots, std::min(kbuffer_texels * view_slots, most));
  if (wanted > kbuffer_fragments) {
    kbuffer_fragments = wanted;
    gl.NamedBufferData(fragment_buffer, GLsizeiptr(kbuffer_fragments * 16), nullptr, GL_DYNAMIC_COPY);
    gl.TextureBuffer(fragment_tex, GL_RGBA32UI, fragment_buffer);
  }
}

void GlImageStage::Impl::ensure_fragments(std::size_t fragments) {
  if (fragments <= kbuffer_fragments) return;
  kbuffer_fragments = std::max(fragments, kbuffer_fragments * 3 / 2);
  gl.NamedBufferData(fragment_buffer, GLsizeiptr(kbuffer_fragments * 16), nullptr, GL_DYNAMIC_COPY);
  gl.TextureBuffer(fragment_tex, GL_RGBA32UI, fragment_buffer);
}

void GlImageStage::Impl::release_layers() {
  if (!layer_size) return;
  gl.DeleteFramebuffers(2, fbo);
  gl.DeleteTextures(2, layer_tex);
  gl.DeleteTextures(1, &run_tex);
  gl.DeleteRenderbuffers(1, &depth_rb);
  layer_size = 0;
}

// Two ping-pong layer textures (RGBA32UI, see shaders/peel.frag) sharing one depth buffer,
// and the run-start texture of full peeling (shaders/pcs.comp).
void GlImageStage::Impl::ensure_layers(int n) {
  if (n == layer_size) return;
  release_layers();
  gl.CreateTextures(GL_TEXTURE_2D, 2, layer_tex);
  gl.CreateTextures(GL_TEXTURE_2D, 1, &run_tex);
  gl.TextureStorage2D(run_tex, 1, GL_RGBA32UI, n, n);
  gl.CreateRenderbuffers(1, &depth_rb);
  gl.NamedRenderbufferStorage(depth_rb, GL_DEPTH_COMPONENT32F, n, n);
  gl.CreateFramebuffers(2, fbo);
  for (int i = 0; i < 2; ++i) {
    gl.TextureStorage2D(layer_tex[i], 1, GL_RGBA32UI, n, n);
    gl.TextureParameteri(layer_tex[i], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TextureParameteri(layer_tex[i], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl.NamedFramebufferTexture(fbo[i], GL_COLOR_ATTACHMENT0, layer_tex[i], 0);
    gl.NamedFramebufferRenderbuffer(fbo[i], GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
    if (gl.CheckNamedFramebufferStatus(fbo[i], GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw GlError("peelcd::gl::GlImageStage: layer framebuffer of " + std::to_string(n) + "^2 is incomplete");
  }
  layer_size = n;
  check("layer allocation");
}

// The k-buffer draw writes storage buffers only: a framebuffer without attachments (no
// colour or depth tiles for a software rasterizer to load and store). Only its size follows
// the tile (which changes with the number of ROIs and their triangles' size); the layer
// textures, which the k-buffer does not need, are not reallocated for it.
void GlImageStage::Impl::ensure_bare_fbo(int n) {
  if (bare_fbo == 0) gl.CreateFramebuffers(1, &bare_fbo);
  if (n == bare_size) return;
  gl.NamedFramebufferParameteri(bare_fbo, GL_FRAMEBUFFER_DEFAULT_WIDTH, n);
  gl.NamedFramebufferParameteri(bare_fbo, GL_FRAMEBUFFER_DEFAULT_HEIGHT, n);
  if (gl.CheckNamedFramebufferStatus(bare_fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlError("peelcd::gl::GlImageStage: attachment-less framebuffer of " + std::to_string(n) + "^2 is incomplete");
  bare_size = n;
  check("framebuffer resize");
}

}  // namespace peelcd::gl
