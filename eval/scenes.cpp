#include "peelcd/eval/scenes.h"

#include "peelcd/core/aabb.h"
#include "peelcd/core/primitives.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/mesh_io.h"

#include <algorithm>
#include <cmath>
#include <Eigen/Geometry>
#include <map>

namespace peelcd {
namespace {

Aabb bounds_of(const Mesh& m) {
  Aabb b{m.vertices[0], m.vertices[0]};
  for (const Vec3& v : m.vertices) {
    b.lo = b.lo.cwiseMin(v);
    b.hi = b.hi.cwiseMax(v);
  }
  return b;
}

class Test1 final : public Sequence {
 public:
  Test1(const std::string& dir, std::size_t frames, bool rigid) : Sequence(frames), rigid_(rigid) {
    raptor_ = load_mesh(dir + "/velociraptor.obj");  // 1,248 triangles, long axis z, feet at y = 0
    ball_ = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), kRadius, 48, 48));  // 4,512 triangles
    // 4 columns x 10 rows on the table (y = 0), 0.04 apart: the balls never touch each other.
    for (int row = 0; row < 10; ++row)
      for (int col = 0; col < 4; ++col)
        centres_.emplace_back(-0.9 + 0.6 * col, kRadius, -3.6 + 0.8 * row);
  }
  std::string name() const override { return "test1"; }
  int phases() const override { return 4; }

  void frame(std::size_t f, std::vector<Object>& objects) const override {
    objects.resize(41);
    const double s = frames_ > 1 ? double(f) / double(frames_ - 1) : 0.0;
    // Walk along +z from outside the field into it; in the last half, crouch by up to 0.45.
    const double z = -6.0 + 6.5 * std::min(1.0, 1.6 * s);
    const double crouch = 0.45 * std::clamp(2.0 * s - 1.0, 0.0, 1.0);
    const double phase = 0.6 * double(f);
    Object& r = objects[0];
    r.name = "raptor";
    r.mesh.triangles = raptor_.triangles;
    r.mesh.vertices.resize(raptor_.vertices.size());
    for (std::size_t i = 0; i < raptor_.vertices.size(); ++i) {
      const Vec3& p = raptor_.vertices[i];
      const double swing = 0.12 * (1.0 - p.y() / 1.6) * std::sin(2.0 * M_PI * p.z() / 1.8 - phase);
      r.mesh.vertices[i] = Vec3(p.x() + swing, p.y() - crouch, p.z() + z);
    }
    for (std::size_t k = 0; k < centres_.size(); ++k) {
      Object& b = objects[k + 1];
      b.name = "ball" + std::to_string(k);
      b.mesh.triangles = ball_->triangles;
      b.mesh.vertices.resize(ball_->vertices.size());
      for (std::size_t i = 0; i < ball_->vertices.size(); ++i) b.mesh.vertices[i] = ball_->vertices[i] + centres_[k];
      if (rigid_) b.rigid = RigidMotion{ball_, Eigen::Affine3d(Eigen::Translation3d(centres_[k]))};
      else b.rigid.reset();
    }
  }

 private:
  static constexpr double kRadius = 0.28;
  bool rigid_;
  Mesh raptor_;
  std::shared_ptr<const Mesh> ball_;
  std::vector<Vec3> centres_;
};

class Test2 final : public Sequence {
 public:
  Test2(const std::string& dir, std::size_t frames, bool rigid) : Sequence(frames), rigid_(rigid) {
    const char* names[] = {"bunny_3k.obj", "dragon_3k.obj", "fish_2k.obj", "kitten_1k5.obj", "torus.obj",
                           "velociraptor.obj"};
    for (const char* n : names) {
      Mesh m = load_mesh(dir + "/" + n);
      // Normalise: centred, longest side 0.9.
      const Aabb b = bounds_of(m);
      const Vec3 c = 0.5 * (b.lo + b.hi);
      const double side = (b.hi - b.lo).maxCoeff();
      for (Vec3& v : m.vertices) v = (v - c) * (0.9 / side);
      shapes_.push_back(std::make_shared<const Mesh>(std::move(m)));
      shape_names_.push_back(std::string(n).substr(0, std::string(n).find('_') == std::string::npos
                                                          ? std::string(n).find('.')
                                                          : std::string(n).find('_')));
    }
    // 40 objects over a 5 x 8 grid above the cloth, 0.95 apart in x (the 0.9 objects nearly
    // touch), staggered in height so they reach the cloth at different frames; every fifth one
    // is shifted onto its neighbour so that pairs of falling objects collide too.
    for (int i = 0; i < 40; ++i) {
      const int col = i % 5, row = i / 5;
      Vec3 p(-1.9 + 0.95 * col, 0.85 + 0.35 * ((i * 7) % 11), -2.6 + 0.75 * row);
      if (i % 5 == 4) p.x() -= 0.45;
      starts_.push_back(p);
      spin_.push_back(0.3 + 0.1 * (i % 7));
    }
  }
  std::string name() const override { return "test2"; }
  int phases() const override { return 8; }

  void frame(std::size_t f, std::vector<Object>& objects) const override {
    objects.resize(41);
    const double s = frames_ > 1 ? double(f) / double(frames_ - 1) : 0.0;
    Object& cloth = objects[0];
    cloth.name = "cloth";
    cloth.mesh = torn_cloth(28, s, 0.0);
    for (std::size_t i = 0; i < starts_.size(); ++i) {
      Object& o = objects[i + 1];
      const Mesh& m = *shapes_[i % shapes_.size()];
      o.name = shape_names_[i % shapes_.size()] + std::to_string(i);
      o.mesh.triangles = m.triangles;
      o.mesh.vertices.resize(m.vertices.size());
      const double y = starts_[i].y() - 5.0 * s;  // falls 5 units over the sequence
      const double a = spin_[i] * double(f) * 0.2, ca = std::cos(a), sa = std::sin(a);
      for (std::size_t k = 0; k < m.vertices.size(); ++k) {
        const Vec3& v = m.vertices[k];
        o.mesh.vertices[k] = Vec3(ca * v.x() + sa * v.z() + starts_[i].x(), v.y() + y, -sa * v.x() + ca * v.z() + starts_[i].z());
      }
      if (rigid_) {
        Eigen::Matrix3d r;
        r << ca, 0, sa, 0, 1, 0, -sa, 0, ca;
        Eigen::Affine3d pose = Eigen::Affine3d::Identity();
        pose.linear() = r;
        pose.translation() = Vec3(starts_[i].x(), y, starts_[i].z());
        o.rigid = RigidMotion{shapes_[i % shapes_.size()], pose};
      } else {
        o.rigid.reset();
      }
    }
  }

 private:
  std::vector<std::shared_ptr<const Mesh>> shapes_;
  std::vector<std::string> shape_names_;
  std::vector<Vec3> starts_;
  std::vector<double> spin_;
  bool rigid_;
};

}  // namespace

Mesh torn_cloth(int n, double t, double y) {
  Mesh grid = make_grid(Vec3(-3, y, -3), Vec3(6, 0, 0), Vec3(0, 0, 6), n, n);
  for (Vec3& v : grid.vertices) v.y() = y + 0.08 * std::sin(1.5 * v.x()) * std::cos(v.z());
  constexpr double kTearX = 0.05;
  const double tear_end = -3.0 + 6.0 * std::clamp(t, 0.0, 1.0);
  Mesh out;
  out.vertices = grid.vertices;
  // Split the triangles the tear crosses at their centroid.
  std::vector<Tri> tris;
  for (const Tri& tri : grid.triangles) {
    double lo = 1e300, hi = -1e300, zmin = 1e300;
    for (std::uint32_t i : tri) {
      lo = std::min(lo, grid.vertices[i].x());
      hi = std::max(hi, grid.vertices[i].x());
      zmin = std::min(zmin, grid.vertices[i].z());
    }
    if (lo < kTearX && kTearX < hi && zmin < tear_end) {
      const Vec3 c = (grid.vertices[tri[0]] + grid.vertices[tri[1]] + grid.vertices[tri[2]]) / 3.0;
      out.vertices.push_back(c);
      const auto ci = std::uint32_t(out.vertices.size() - 1);
      tris.push_back({tri[0], tri[1], ci});
      tris.push_back({tri[1], tri[2], ci});
      tris.push_back({tri[2], tri[0], ci});
    } else {
      tris.push_back(tri);
    }
  }
  // Beyond the tear the cloth gets its own vertices, pulled sideways and down.
  std::map<std::uint32_t, std::uint32_t> dup;
  for (Tri& tri : tris) {
    const Vec3 c = (out.vertices[tri[0]] + out.vertices[tri[1]] + out.vertices[tri[2]]) / 3.0;
    if (c.x() <= kTearX || c.z() >= tear_end) continue;
    for (std::uint32_t& i : tri) {
      const Vec3 p = out.vertices[i];
      if (p.x() < kTearX - 1e-12) continue;
      auto it = dup.find(i);
      if (it == dup.end()) {
        const double open = std::max(0.0, tear_end - p.z()) / 6.0;  // wider where torn longer ago
        out.vertices.push_back(Vec3(p.x() + 0.15 * open, p.y() - 0.5 * open, p.z()));
        it = dup.emplace(i, std::uint32_t(out.vertices.size() - 1)).first;
      }
      i = it->second;
    }
  }
  out.triangles = std::move(tris);
  // Drop vertices no triangle uses (the originals replaced everywhere by their duplicates).
  std::vector<std::int64_t> remap(out.vertices.size(), -1);
  Mesh packed;
  for (Tri& tri : out.triangles)
    for (std::uint32_t& i : tri) {
      if (remap[i] < 0) {
        remap[i] = std::int64_t(packed.vertices.size());
        packed.vertices.push_back(out.vertices[i]);
      }
      i = std::uint32_t(remap[i]);
    }
  packed.triangles = std::move(out.triangles);
  return packed;
}

class Crowd final : public Sequence {
 public:
  Crowd(std::size_t count, std::size_t frames, bool rigid) : Sequence(frames), rigid_(rigid) {
    ball_ = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), kRadius, 12, 24));
    // Lower layer: side x side grid; upper layer: (side - 1)^2 in its hollows; filled lower first.
    std::size_t side = 1;
    while (side * side + (side - 1) * (side - 1) < count) ++side;
    const double d = 2.0 * kRadius * 0.99;
    for (std::size_t k = 0; k < side * side && centres_.size() < count; ++k)
      centres_.emplace_back(d * double(k % side), d * double(k / side), 0.0);
    // A ball in the hollow of four touching a distance 2r - 0.01 from each: height h with
    // (d/sqrt2)^2 + h^2 = (2r - 0.01)^2.
    const double reach = 2.0 * kRadius - 0.01;
    const double h = std::sqrt(reach * reach - d * d / 2.0);
    for (std::size_t k = 0; k < (side - 1) * (side - 1) && centres_.size() < count; ++k)
      centres_.emplace_back(d * (double(k % (side - 1)) + 0.5), d * (double(k / (side - 1)) + 0.5), h);
  }
  std::string name() const override { return "crowd"; }
  int phases() const override { return 1; }

  void frame(std::size_t f, std::vector<Object>& objects) const override {
    objects.resize(centres_.size());
    for (std::size_t k = 0; k < centres_.size(); ++k) {
      Object& o = objects[k];
      o.name = "ball" + std::to_string(k);
      const double t = 0.7 * double(f) + 1.3 * double(k);
      const Vec3 at = centres_[k] + 0.004 * Vec3(std::sin(t), std::cos(1.1 * t), 0.5 * std::sin(0.9 * t));
      const Eigen::Affine3d pose =
          Eigen::Translation3d(at) * Eigen::AngleAxisd(0.05 * double(f) + double(k), Vec3(0.3, 0.5, 0.8).normalized());
      const bool breathing = k % 5 == 4;
      const double scale = breathing ? 1.0 + 0.002 * std::sin(t) : 1.0;
      o.mesh.triangles = ball_->triangles;
      o.mesh.vertices.resize(ball_->vertices.size());
      for (std::size_t i = 0; i < ball_->vertices.size(); ++i) o.mesh.vertices[i] = pose * (scale * ball_->vertices[i]);
      if (rigid_ && !breathing) o.rigid = RigidMotion{ball_, pose};
      else o.rigid.reset();
    }
  }

 private:
  static constexpr double kRadius = 0.5;
  bool rigid_;
  std::shared_ptr<const Mesh> ball_;
  std::vector<Vec3> centres_;
};

class CrossingSpheres final : public Sequence {
 public:
  CrossingSpheres(int stacks, std::size_t frames, bool wave, bool rigid)
      : Sequence(frames), stacks_(stacks), wave_(wave), rigid_(rigid) {
    ball_ = std::make_shared<const Mesh>(make_uv_sphere(Vec3::Zero(), 1.0, stacks, 2 * stacks));
  }
  std::string name() const override { return "spheres"; }
  int phases() const override { return 1; }

  void frame(std::size_t f, std::vector<Object>& objects) const override {
    objects.resize(2);
    for (std::size_t k = 0; k < 2; ++k) {
      Object& o = objects[k];
      o.name = k ? "sphere B" : "sphere A";
      const double t = 0.37 * double(f) + 2.1 * double(k);
      const Vec3 at(k ? 0.6 : -0.6, 0.01 * std::sin(t), 0.01 * std::cos(1.3 * t));
      const Eigen::Affine3d pose =
          Eigen::Translation3d(at) *
          Eigen::AngleAxisd(0.02 * double(f) + 0.7 * double(k), (k ? Vec3(0.2, 0.9, 0.4) : Vec3(0.8, 0.3, 0.5)).normalized());
      if (o.mesh.triangles.size() != ball_->triangles.size()) o.mesh.triangles = ball_->triangles;
      o.mesh.vertices.resize(ball_->vertices.size());
      if (wave_) {
        // A wave over the surface: the radius along each vertex's direction, moving with f.
        const double phase = 0.5 * double(f);
        for (std::size_t i = 0; i < ball_->vertices.size(); ++i) {
          const Vec3& v = ball_->vertices[i];
          const double r = 1.0 + 0.01 * std::sin(9.0 * v.x() + phase) * std::cos(7.0 * v.y() - 0.5 * phase);
          o.mesh.vertices[i] = pose * (r * v);
        }
        o.rigid.reset();
      } else {
        for (std::size_t i = 0; i < ball_->vertices.size(); ++i) o.mesh.vertices[i] = pose * ball_->vertices[i];
        if (rigid_) o.rigid = RigidMotion{ball_, pose};
        else o.rigid.reset();
      }
    }
  }

 private:
  int stacks_;
  bool wave_, rigid_;
  std::shared_ptr<const Mesh> ball_;
};

std::unique_ptr<Sequence> make_crossing_spheres(int stacks, std::size_t frames, bool wave, bool rigid) {
  return std::make_unique<CrossingSpheres>(stacks, frames, wave, rigid);
}

namespace {
class FoldingCloth final : public Sequence {
 public:
  FoldingCloth(int n, std::size_t frames, bool rigid) : Sequence(frames), n_(n), rigid_(rigid) {
    ball_ = std::make_shared<const Mesh>(uv_sphere(Vec3(0.5, 0.5, -0.3), 0.35, 32, 16));
  }
  std::string name() const override { return "cloth"; }
  int phases() const override { return 2; }
  void frame(std::size_t f, std::vector<Object>& objects) const override {
    objects.resize(2);
    const double t = frames_ > 1 ? double(f) / double(frames_ - 1) : 1.0;
    Object& cloth = objects[0];
    cloth.name = "cloth";
    cloth.self = true;
    cloth.rigid.reset();
    cloth.mesh = make_folded_sheet(n_, 0.3 * (1.2 - t), 0.4 * t);
    const double drop = 0.5 * std::max(0.0, 1.0 - 2.0 * t);  // on the ball from halfway
    for (Vec3& v : cloth.mesh.vertices) v.z() += drop;
    Object& ball = objects[1];
    ball.name = "ball";
    ball.mesh = *ball_;
    if (rigid_) ball.rigid = RigidMotion{ball_, Eigen::Affine3d::Identity()};
  }

 private:
  int n_;
  bool rigid_;
  std::shared_ptr<const Mesh> ball_;
};
}  // namespace

std::unique_ptr<Sequence> make_folding_cloth(int n, std::size_t frames, bool rigid) {
  return std::make_unique<FoldingCloth>(n, frames, rigid);
}

std::unique_ptr<Sequence> make_crowd(std::size_t objects, std::size_t frames, bool rigid) {
  return std::make_unique<Crowd>(objects, frames, rigid);
}

std::unique_ptr<Sequence> make_test1(const std::string& dir, std::size_t frames, bool rigid) {
  return std::make_unique<Test1>(dir, frames, rigid);
}
std::unique_ptr<Sequence> make_test2(const std::string& dir, std::size_t frames, bool rigid) {
  return std::make_unique<Test2>(dir, frames, rigid);
}

}  // namespace peelcd
