// An animation loop: 100 frames, one mesh deforming in place, one rigid mesh moved by its pose,
// on a GL context the application created itself (here OSMesa) and hands to peelcd through
// peelcd::gl::Context. The application's context is current again after every frame.
#include "core/mesh.h"  // this project's own header

#include <GL/osmesa.h>
#include <peelcd/peelcd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

// The application's own GL context, given to peelcd.
class AppContext final : public peelcd::gl::Context {
 public:
  AppContext() {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!ctx_) throw peelcd::gl::GlError("no OSMesa 4.5 core context");
  }
  ~AppContext() override { OSMesaDestroyContext(ctx_); }
  void make_current() override {
    previous_ = OSMesaGetCurrentContext();
    if (previous_ == ctx_) previous_ = nullptr;
    else if (previous_) OSMesaGetColorBuffer(previous_, &w_, &h_, &format_, &buffer_);
    if (!OSMesaMakeCurrent(ctx_, pixel_, GL_UNSIGNED_BYTE, 1, 1)) throw peelcd::gl::GlError("OSMesaMakeCurrent");
  }
  void restore_previous() noexcept override {
    if (previous_) OSMesaMakeCurrent(previous_, buffer_, GL_UNSIGNED_BYTE, w_, h_);
    previous_ = nullptr;
  }
  peelcd::gl::ProcAddress proc_address(const char* name) override {
    return reinterpret_cast<peelcd::gl::ProcAddress>(OSMesaGetProcAddress(name));
  }
  std::string backend() const override { return "app-osmesa"; }

 private:
  OSMesaContext ctx_ = nullptr, previous_ = nullptr;
  unsigned char pixel_[4] = {};
  GLint w_ = 0, h_ = 0, format_ = 0;
  void* buffer_ = nullptr;
};

peelcd::Mesh sphere(double r, int rings, int segments) {
  peelcd::Mesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double t = M_PI * i / rings, p = 2 * M_PI * j / segments;
      m.vertices.emplace_back(r * std::sin(t) * std::cos(p), r * std::sin(t) * std::sin(p), r * std::cos(t));
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const auto a = std::uint32_t(i * segments + j), b = std::uint32_t(i * segments + (j + 1) % segments);
      const auto c = a + std::uint32_t(segments), d = b + std::uint32_t(segments);
      if (i > 0) m.triangles.push_back({a, c, b});
      if (i < rings - 1) m.triangles.push_back({b, c, d});
    }
  return m;
}

}  // namespace

int main() {
  const app::Mesh mine{2};
  auto context = std::make_shared<AppContext>();
  auto stage = std::make_shared<peelcd::gl::GlImageStage>(context);
  auto detector = std::make_shared<peelcd::Detector>(stage);

  const peelcd::Mesh rest = sphere(1.0, 16, 32);
  peelcd::CollisionObject blob = peelcd::CollisionObject::deforming(rest, "blob");
  auto ball_shape = std::make_shared<const peelcd::CollisionGeometry>(sphere(0.5, 12, 24), "ball");
  peelcd::CollisionObject ball(ball_shape, Eigen::Affine3d::Identity(), "ball");
  peelcd::CollisionWorld world(detector);
  world.add(&blob);
  world.add(&ball);

  std::vector<double> ms;
  std::size_t contacts = 0;
  for (int f = 0; f < 100; ++f) {
    const double s = 2 * M_PI * f / 100.0;
    for (std::size_t i = 0; i < rest.vertices.size(); ++i) {  // the blob breathes, in place
      const peelcd::Vec3& v = rest.vertices[i];
      blob.deforming_vertices()[i] = v * (1.0 + 0.1 * std::sin(3 * s + 4 * v.z()));
    }
    ball.set_pose(Eigen::Affine3d(Eigen::Translation3d(1.2 * std::cos(s), 1.2 * std::sin(s), 0.2)));
    const auto t0 = std::chrono::steady_clock::now();
    const peelcd::FrameResult& r = world.detect();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    for (const peelcd::PairResult& p : r.pairs) contacts += p.colliding.size();
  }
  std::sort(ms.begin(), ms.end());
  std::printf("peelcd %s on %s (%s): 100 frames, %zu contacts in all, median %.2f ms a frame (app mesh %d)\n",
              peelcd::version_string(), stage->renderer().c_str(), stage->backend().c_str(), contacts, ms[50],
              mine.id);
  return contacts > 0 ? 0 : 1;
}
