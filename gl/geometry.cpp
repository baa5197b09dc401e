// A view's triangles into GL buffers: a world-space object's corners in ROI-local floats
// (shifted by the ROI centre in double, rounded once), or a rigid object's shape cached on the
// GPU with only the corner indices of its triangles in the view.
#include "stage_impl.h"

namespace peelcd::gl {

void GlImageStage::Impl::prepare(const Object& object, const RoiView& view, const std::vector<std::uint32_t>& triangles,
                                 IdMode ids, int slot) {
  const Mesh& mesh = drawn_mesh(object);
  if (!object.rigid || !object.rigid->shape) {
    slot_shape[slot] = nullptr;
    std::vector<GpuVertex>& out = staging[slot];
    out.clear();
    for (const std::uint32_t t : triangles)
      for (int k = 0; k < 3; ++k) {
        const Vec3 local = mesh.vertices[mesh.triangles[t][k]] - view.center;
        out.push_back({float(local.x()), float(local.y()), float(local.z()), corner_id(mesh, t, k, ids)});
      }
    return;
  }
  std::vector<std::uint32_t>& out = indices[slot];
  out.clear();
  for (const std::uint32_t t : triangles)
    for (std::uint32_t k = 0; k < 3; ++k) out.push_back(3 * t + k);
  slot_shape[slot] = &cached_shape(object.rigid->shape, ids);
  // ROI-local from shape-local, composed in double, rounded once.
  Eigen::Affine3d m = object.rigid->pose;
  m.translation() -= view.center;
  const Eigen::Matrix4d mm = m.matrix();
  for (int i = 0; i < 16; ++i) slot_model[slot][i] = float(mm(i % 4, i / 4));
}

void GlImageStage::Impl::set_view_uniforms(GLint u_clip_, GLint u_lo, GLint u_hi, const RoiView& view) {
  const std::array<float, 16> m = view.clip_from_local();
  const Vec3 lo = view.box.lo - view.center, hi = view.box.hi - view.center;
  gl.UniformMatrix4fv(u_clip_, 1, GL_FALSE, m.data());
  gl.Uniform3f(u_lo, float(lo.x()), float(lo.y()), float(lo.z()));
  gl.Uniform3f(u_hi, float(hi.x()), float(hi.y()), float(hi.z()));
}

// The GPU copy of a rigid shape (every triangle's corners in shape-local floats, with IDs),
// uploaded the first time it is seen with this ID mode. Shapes no longer held are dropped.
const GlImageStage::Impl::CachedShape& GlImageStage::Impl::cached_shape(const std::shared_ptr<const Mesh>& shape, IdMode ids) {
  auto it = shapes.find({shape.get(), ids});
  if (it != shapes.end() && !it->second.owner.expired()) return it->second;
  if (it != shapes.end()) {
    gl.DeleteBuffers(1, &it->second.vbo);
    shapes.erase(it);
  }
  std::vector<GpuVertex> corners_local;
  corners_local.reserve(shape->triangles.size() * 3);
  for (std::uint32_t t = 0; t < shape->triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = shape->vertices[shape->triangles[t][k]];
      corners_local.push_back({float(p.x()), float(p.y()), float(p.z()), corner_id(*shape, t, k, ids)});
    }
  CachedShape c;
  c.owner = shape;
  c.corners = corners_local.size();
  c.provoking_ids.reserve(c.corners / 3);
  for (std::size_t i = 2; i < corners_local.size(); i += 3) c.provoking_ids.push_back(corners_local[i].id);
  gl.CreateBuffers(1, &c.vbo);
  gl.NamedBufferData(c.vbo, GLsizeiptr(corners_local.size() * sizeof(GpuVertex)), nullptr, GL_STATIC_DRAW);
  upload_geometry(c.vbo, 0, GLsizeiptr(corners_local.size() * sizeof(GpuVertex)), corners_local.data());
  ++shape_uploads;
  return shapes.emplace(std::make_pair(shape.get(), ids), std::move(c)).first->second;
}

void GlImageStage::Impl::drop_expired_shapes() {
  for (auto it = shapes.begin(); it != shapes.end();) {
    if (it->second.owner.expired()) {
      gl.DeleteBuffers(1, &it->second.vbo);
      it = shapes.erase(it);
    } else {
      ++it;
    }
  }
}

// Draws slot `slot` with the current program, whose roi_from_object is at `u_model`.
void GlImageStage::Impl::draw(int slot, GLint u_model) {
  static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  if (!slot_shape[slot]) {
    gl.UniformMatrix4fv(u_model, 1, GL_FALSE, identity);
    gl.VertexArrayVertexBuffer(vao, 0, vbo[slot], 0, sizeof(GpuVertex));
    timed_draw([&] { gl.DrawArrays(GL_TRIANGLES, 0, GLsizei(staging[slot].size())); });
    return;
  }
  gl.UniformMatrix4fv(u_model, 1, GL_FALSE, slot_model[slot].data());
  gl.VertexArrayVertexBuffer(vao, 0, slot_shape[slot]->vbo, 0, sizeof(GpuVertex));
  gl.VertexArrayElementBuffer(vao, ibo[slot]);
  timed_draw([&] { gl.DrawElements(GL_TRIANGLES, GLsizei(indices[slot].size()), GL_UNSIGNED_INT, nullptr); });
}

void GlImageStage::Impl::upload(int slot) {
  if (slot_shape[slot]) {  // a rigid shape: only the indices
    const std::size_t n = indices[slot].size();
    if (n > ibo_capacity[slot]) {
      ibo_capacity[slot] = std::max<std::size_t>(n, ibo_capacity[slot] * 3 / 2);
      gl.NamedBufferData(ibo[slot], ibo_capacity[slot] * sizeof(std::uint32_t), nullptr, GL_STREAM_DRAW);
    }
    upload_geometry(ibo[slot], 0, n * sizeof(std::uint32_t), indices[slot].data());
    return;
  }
  const std::size_t n = staging[slot].size();
  if (n > vbo_capacity[slot]) {
    vbo_capacity[slot] = std::max<std::size_t>(n, vbo_capacity[slot] * 3 / 2);
    gl.NamedBufferData(vbo[slot], vbo_capacity[slot] * sizeof(GpuVertex), nullptr, GL_STREAM_DRAW);
  }
  upload_geometry(vbo[slot], 0, n * sizeof(GpuVertex), staging[slot].data());
}

}  // namespace peelcd::gl
