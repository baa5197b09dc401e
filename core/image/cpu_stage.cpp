#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/clock.h"

#include "peelcd/core/image/conservative.h"
#include "peelcd/core/image/texel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

namespace peelcd {
namespace {

// Sub-texel precision of the rasterizer: vertices snap to 1/256 of a texel (llvmpipe's
// FIXED_ORDER).
constexpr double kSubTexel = 256.0;


}  // namespace

struct CpuImageStage::Corner {
  Eigen::Vector3d local;  // ROI-local position after the float vertex stage
  double x, y;            // window position, texels
  float z;                // window depth
  std::int64_t fx, fy;    // snapped, relative to texel centres: texel i's centre is at i * 256
};

StageCost CpuImageStage::cost() const {
  // Fitted by `peelcd calibrate --backend cpu` on the machine docs/performance.md names.
  return StageCost{0.0, 0.85, 20.0};
}

// A view as the GL stage draws it: the objects' triangles through the float vertex stage into
// fragments (point sampling with the top-left rule, or conservative coverage with depth
// intervals), then the k-buffer resolved as the GL stage's host resolve does.
void CpuImageStage::peel(const PeelJob& job, PeelResult& out, Timings& timings) {
  out.clear();
  const auto t0 = Clock::now();
  fragments_.clear();
  for (int slot = 0; slot < 2; ++slot) raster_object(job, slot);
  timings.upload += ms_since(t0);
  const auto t1 = Clock::now();
  resolve(job, out);
  timings.gpu += ms_since(t1);
}

// One object's triangles of the view: corners through the vertex stage (a rigid object: its
// shape in floats moved by the pose rounded to floats, as uploaded), then rasterized.
void CpuImageStage::raster_object(const PeelJob& job, int slot) {
  const RoiView& view = job.view;
  const int n = view.resolution;
  const std::array<float, 16> m = view.clip_from_local();  // column-major, as the shader gets it
  const Vec3 lo_d = view.box.lo - view.center, hi_d = view.box.hi - view.center;
  const float box_lo[3] = {float(lo_d.x()), float(lo_d.y()), float(lo_d.z())};
  const float box_hi[3] = {float(hi_d.x()), float(hi_d.y()), float(hi_d.z())};
  const double half_n = 0.5 * n;
  const Object& object = *job.objects[slot];
  const Mesh& mesh = drawn_mesh(object);
  const std::vector<std::uint32_t>& tris = job_triangles(job, slot, selected_[slot]);
  drawn_[slot] = tris.size();
  std::vector<std::uint32_t>& ids = ids_[slot];
  ids.resize(tris.size());
  Eigen::Matrix4f model = Eigen::Matrix4f::Identity();
  const bool rigid = object.rigid && object.rigid->shape;
  if (rigid) {
    Eigen::Affine3d pose = object.rigid->pose;
    pose.translation() -= view.center;
    model = pose.matrix().cast<float>();
  }
  float grow_x = 0.0f, grow_z = 0.0f;  // proximity: every triangle grown by PeelJob::grow
  conservative::grow_of(job.grow, view.texel(), 2.0 * view.half_depth, grow_x, grow_z);
  for (std::size_t order = 0; order < tris.size(); ++order) {
    const std::uint32_t t = tris[order];
    ids[order] = corner_id(rigid ? *object.rigid->shape : mesh, t, 2, job.ids);
    Corner c[3];
    conservative::Triangle ct;
    float err[3] = {0.0f, 0.0f, 0.0f};  // |M| P + |M_t| per clip coordinate (the margins)
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3f p, mag;
      if (rigid) {
        const Vec3& s = object.rigid->shape->vertices[object.rigid->shape->triangles[t][k]];
        const Eigen::Vector4f sv(float(s.x()), float(s.y()), float(s.z()), 1.0f);
        const Eigen::Vector4f q = model * sv;
        p = q.head<3>();
        mag = model.block<3, 3>(0, 0).cwiseAbs() * sv.head<3>().cwiseAbs() + model.block<3, 1>(0, 3).cwiseAbs();
      } else {
        const Vec3 local = mesh.vertices[mesh.triangles[t][k]] - view.center;
        p = Eigen::Vector3f(float(local.x()), float(local.y()), float(local.z()));
        mag = p.cwiseAbs();
      }
      c[k].local = p.cast<double>();
      const float cx = m[0] * p.x() + m[4] * p.y() + m[8] * p.z() + m[12];
      const float cy = m[1] * p.x() + m[5] * p.y() + m[9] * p.z() + m[13];
      const float cz = m[2] * p.x() + m[6] * p.y() + m[10] * p.z() + m[14];
      if (job.conservative) {
        for (int r = 0; r < 3; ++r)
          err[r] = std::max(err[r], std::fabs(m[r]) * mag.x() + std::fabs(m[4 + r]) * mag.y() +
                                        std::fabs(m[8 + r]) * mag.z() + std::fabs(m[12 + r]));
        ct.x[k] = (cx + 1.0f) * (0.5f * float(n));
        ct.y[k] = (cy + 1.0f) * (0.5f * float(n));
        ct.z[k] = 0.5f * cz + 0.5f;
      }
      c[k].x = (double(cx) + 1.0) * half_n;
      c[k].y = (double(cy) + 1.0) * half_n;
      c[k].z = float(0.5 * double(cz) + 0.5);
      c[k].fx = std::llround((c[k].x - 0.5) * kSubTexel);
      c[k].fy = std::llround((c[k].y - 0.5) * kSubTexel);
    }
    const std::uint32_t key = (std::uint32_t(slot) << 31) | std::uint32_t(order);
    if (job.conservative) {
      conservative::set_margins(ct, err[0], err[1], err[2], n, grow_x, grow_z);
      raster_conservative(ct, n, key);
    } else {
      raster_point(c, n, key, box_lo, box_hi);
    }
  }
}

// Point sampling at texel centres, as rasterization does: both windings (no face culling), the
// top-left rule, depth and ROI-local position interpolated over the snapped triangle, clipped by
// the ROI box at the sample (the shader's clip distances).
void CpuImageStage::raster_point(const Corner (&c)[3], int n, std::uint32_t key, const float box_lo[3],
                                 const float box_hi[3]) {
  std::int64_t area = (c[1].fx - c[0].fx) * (c[2].fy - c[0].fy) - (c[2].fx - c[0].fx) * (c[1].fy - c[0].fy);
  if (area == 0) return;  // no area on screen: no fragment, as in rasterization
  int order_idx[3] = {0, 1, 2};
  if (area < 0) {
    std::swap(order_idx[1], order_idx[2]);
    area = -area;
  }
  const Corner& a = c[order_idx[0]];
  const Corner& b = c[order_idx[1]];
  const Corner& d = c[order_idx[2]];
  const Corner* e0[3] = {&a, &b, &d};
  const Corner* e1[3] = {&b, &d, &a};
  // Top-left rule (counter-clockwise in y-up window coordinates): an edge owns the texel centres
  // on it when it is a left edge (going down) or a top edge (horizontal, going left).
  std::int64_t bias[3];
  for (int k = 0; k < 3; ++k) {
    const std::int64_t dx = e1[k]->fx - e0[k]->fx, dy = e1[k]->fy - e0[k]->fy;
    const bool owns = dy < 0 || (dy == 0 && dx < 0);
    bias[k] = owns ? 0 : -1;
  }
  const std::int64_t min_x = std::min({a.fx, b.fx, d.fx}), max_x = std::max({a.fx, b.fx, d.fx});
  const std::int64_t min_y = std::min({a.fy, b.fy, d.fy}), max_y = std::max({a.fy, b.fy, d.fy});
  const auto ceil_div = [](std::int64_t v) { return v >= 0 ? (v + 255) / 256 : -((-v) / 256); };
  const auto floor_div = [](std::int64_t v) { return v >= 0 ? v / 256 : -((-v + 255) / 256); };
  const int i0 = int(std::max<std::int64_t>(0, ceil_div(min_x)));
  const int i1 = int(std::min<std::int64_t>(n - 1, floor_div(max_x)));
  const int j0 = int(std::max<std::int64_t>(0, ceil_div(min_y)));
  const int j1 = int(std::min<std::int64_t>(n - 1, floor_div(max_y)));
  if (i0 > i1 || j0 > j1) return;
  // Depth and position planes over the snapped triangle, per texel.
  const double ax = double(a.fx) / kSubTexel, ay = double(a.fy) / kSubTexel;
  const double bx = double(b.fx) / kSubTexel - ax, by = double(b.fy) / kSubTexel - ay;
  const double dx_ = double(d.fx) / kSubTexel - ax, dy_ = double(d.fy) / kSubTexel - ay;
  const double det = bx * dy_ - dx_ * by;  // = area / 256^2
  const auto plane = [&](double va, double vb, double vd, double& gx, double& gy) {
    gx = ((vb - va) * dy_ - (vd - va) * by) / det;
    gy = ((vd - va) * bx - (vb - va) * dx_) / det;
  };
  double zx, zy;
  plane(a.z, b.z, d.z, zx, zy);
  Eigen::Vector3d px, py;
  for (int k = 0; k < 3; ++k) plane(a.local[k], b.local[k], d.local[k], px[k], py[k]);
  const float fzx = float(zx), fzy = float(zy);
  for (int j = j0; j <= j1; ++j) {
    const std::int64_t sy = std::int64_t(j) * 256;
    for (int i = i0; i <= i1; ++i) {
      const std::int64_t sx = std::int64_t(i) * 256;
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) {
        const std::int64_t ex = e1[k]->fx - e0[k]->fx, ey = e1[k]->fy - e0[k]->fy;
        const std::int64_t w = ex * (sy - e0[k]->fy) - ey * (sx - e0[k]->fx);
        inside = w + bias[k] >= 0;
      }
      if (!inside) continue;
      const double ux = double(i) - ax, uy = double(j) - ay;
      const float z = float(double(a.z) + zx * ux + zy * uy);
      if (!(z < 1.0f)) continue;  // the far plane: never lands (GL_LESS against 1.0)
      bool clipped = false;
      for (int k = 0; k < 3 && !clipped; ++k) {
        const float q = float(a.local[k] + px[k] * ux + py[k] * uy);
        clipped = q - box_lo[k] < 0.0f || box_hi[k] - q < 0.0f;
      }
      if (clipped) continue;
      fragments_.push_back({std::uint32_t(j) * std::uint32_t(n) + std::uint32_t(i),
                            KFragment{texel::bits_of(z), key, texel::bits_of(fzx), texel::bits_of(fzy)}});
    }
  }
}

// The fragments into the k-buffer layout of shaders/abuffer.frag (slot s of texel t at
// s * texels + t), resolved (core/image/kbuffer.cpp).
void CpuImageStage::resolve(const PeelJob& job, PeelResult& out) {
  const RoiView& view = job.view;
  const int n = view.resolution;
  const std::size_t texels = std::size_t(n) * std::size_t(n);
  counts_.assign(texels, 0u);
  for (const Fragment& f : fragments_) ++counts_[f.texel];
  std::uint32_t slots = 1;
  for (const std::uint32_t c : counts_) slots = std::max(slots, c);
  slots_.resize(std::size_t(slots) * texels);
  std::fill(counts_.begin(), counts_.end(), 0u);
  for (const Fragment& f : fragments_) slots_[std::size_t(counts_[f.texel]++) * texels + f.texel] = f.f;
  KBuffer kb;
  kb.counts = counts_.data();
  kb.fragments = slots_.data();
  kb.resolution = n;
  kb.slots = slots;
  KResolveParams p;
  // The conservative test is interval overlap: no epsilon, no slope (recorded as 0, as the GL
  // stage records them).
  out.epsilon_window = job.conservative ? 0.0f : float(view.world_to_window_depth(job.epsilon));
  out.slope = job.conservative ? 0.0f : float(job.slope);
  p.epsilon_window = out.epsilon_window;
  p.slope = out.slope;
  p.full_peel = job.peel == PeelMode::full;
  p.first_object = std::uint32_t(job.first);
  p.conservative = job.conservative;
  p.ids[0] = ids_[0].data();
  p.ids[1] = ids_[1].data();
  const KResolveResult got = resolve_kbuffer(kb, p, out.pcs, scratch_, job.capture ? &out.captured : nullptr);
  out.layers = int(got.max_layers);
  out.peel_passes = 1;
  out.triangles_uploaded = drawn_[0] + drawn_[1];
}

void CpuImageStage::raster_conservative(const conservative::Triangle& t, int n, std::uint32_t key) {
  const float h = 0.5f + t.mx;
  const float xmin = std::min({t.x[0], t.x[1], t.x[2]}) - h, xmax = std::max({t.x[0], t.x[1], t.x[2]}) + h;
  const float ymin = std::min({t.y[0], t.y[1], t.y[2]}) - h, ymax = std::max({t.y[0], t.y[1], t.y[2]}) + h;
  if (!(xmax >= 0.0f && ymax >= 0.0f && xmin <= float(n) && ymin <= float(n))) return;
  // Clamped to the view in float first: a huge margin (a far rigid shape) must not overflow int.
  const auto first = [](float v) { return std::max(0, int(std::floor(std::max(v, 0.0f))) - 1); };
  const auto last = [n](float v) { return std::min(n - 1, int(std::floor(std::min(v, float(n)))) + 1); };
  const int i0 = first(xmin), i1 = last(xmax), j0 = first(ymin), j1 = last(ymax);
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      float lo, hi;
      if (!conservative::texel_interval(t, i, j, lo, hi)) continue;
      fragments_.push_back({std::uint32_t(j) * std::uint32_t(n) + std::uint32_t(i), KFragment{texel::bits_of(lo), key, texel::bits_of(hi), 0u}});
    }
}

}  // namespace peelcd
