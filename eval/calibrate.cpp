#include "peelcd/eval/calibrate.h"
#include "peelcd/core/clock.h"

#include "peelcd/core/world/world.h"
#include "peelcd/eval/scenes.h"

#include <chrono>

#include "peelcd/core/image/cull.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/mesh_io.h"

#include <Eigen/Dense>

#include <algorithm>

namespace peelcd {
namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Least squares y ~ X c with c >= 0: a negative coefficient is dropped (set to 0) and the rest
// refitted, until none is negative.
Eigen::VectorXd fit_nonnegative(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  std::vector<bool> active(std::size_t(x.cols()), true);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(x.cols());
  for (;;) {
    std::vector<int> cols;
    for (int j = 0; j < x.cols(); ++j)
      if (active[std::size_t(j)]) cols.push_back(j);
    if (cols.empty()) return c;
    Eigen::MatrixXd sub(x.rows(), Eigen::Index(cols.size()));
    for (std::size_t k = 0; k < cols.size(); ++k) sub.col(Eigen::Index(k)) = x.col(cols[k]);
    const Eigen::VectorXd s = sub.colPivHouseholderQr().solve(y);
    c.setZero();
    bool negative = false;
    for (std::size_t k = 0; k < cols.size(); ++k) {
      if (s[Eigen::Index(k)] < 0) {
        active[std::size_t(cols[k])] = false;
        negative = true;
      }
      c[cols[k]] = s[Eigen::Index(k)];
    }
    if (!negative) return c;
  }
}

}  // namespace

std::vector<std::pair<std::string, std::vector<Object>>> calibration_scenes(const std::string& meshes_dir) {
  std::vector<std::pair<std::string, std::vector<Object>>> scenes;
  for (const int k : {8, 16, 32, 64, 128}) {
    for (const double gap : {1.9, 1.2}) {  // centres 1.9 (shallow) or 1.2 (deep) radii apart
      std::vector<Object> s;
      s.push_back(named_object("a", uv_sphere(Vec3(0, 0, 0), 1.0, 2 * k, k)));
      s.push_back(named_object("b", uv_sphere(Vec3(gap, 0.1, 0.05), 1.0, 2 * k, k)));
      scenes.emplace_back("spheres " + std::to_string(4 * k * k) + (gap > 1.5 ? " shallow" : " deep"), std::move(s));
    }
  }
  for (const int k : {16, 48}) {
    std::vector<Object> s;
    s.push_back(named_object("a", uv_sphere(Vec3(0, 0, 0), 1.0, 2 * k, k)));
    s.push_back(named_object("copy", uv_sphere(Vec3(0, 0, 0), 1.0, 2 * k, k)));
    scenes.emplace_back("sphere and copy " + std::to_string(4 * k * k), std::move(s));
  }
  const Mesh bunny = load_mesh(meshes_dir + "/bunny_3k.obj");
  const Mesh dragon = load_mesh(meshes_dir + "/dragon_3k.obj");
  Transform t;
  t.scale = 2.5;
  for (const double dx : {0.8, 0.6, 0.4}) {
    t.translate = Vec3(dx, -0.5, 0.0);
    std::vector<Object> s;
    s.push_back(named_object("bunny", bunny));
    s.push_back(named_object("dragon", transformed(dragon, t)));
    scenes.emplace_back("bunny dragon dx " + std::to_string(dx).substr(0, 3), std::move(s));
  }
  return scenes;
}

namespace {

// `repeat` frames of each of `variants` settings in turns, after one untimed frame each (buffers
// grow, shapes upload): frame() runs one frame with the setting use(k) applied and returns its
// time and its GPU passes' time; the row holds the medians.
VariantRow time_in_turns(const std::string& scene, int repeat, int variants, const std::function<void(int)>& use,
                         const std::function<std::pair<double, double>()>& frame) {
  VariantRow row;
  row.scene = scene;
  std::vector<std::vector<double>> ms(static_cast<std::size_t>(variants)), gpu(ms);
  for (int i = -1; i < repeat; ++i)
    for (int k = 0; k < variants; ++k) {
      use(k);
      const auto [frame_ms, gpu_ms] = frame();
      if (i < 0) continue;
      ms[std::size_t(k)].push_back(frame_ms);
      gpu[std::size_t(k)].push_back(gpu_ms);
    }
  for (int k = 0; k < variants; ++k) {
    row.ms.push_back(median_of(ms[std::size_t(k)]));
    row.gpu_ms.push_back(median_of(gpu[std::size_t(k)]));
  }
  return row;
}

}  // namespace

std::vector<VariantRow> time_variants(Detector& detector, const std::string& meshes_dir, int budget, int repeat,
                                      int variants, const std::function<void(int)>& use) {
  std::vector<VariantRow> rows;
  FrameResult r;
  for (const auto& [name, objects] : calibration_scenes(meshes_dir)) {
    DetectOptions opt;
    opt.budget = budget;
    opt.stage = Stage::image;
    rows.push_back(time_in_turns(name, repeat, variants, use, [&] {
      detector.detect(objects, opt, r);
      return std::pair(r.timings.total - r.timings.aabb, r.timings.gpu_raster + r.timings.gpu_compute);
    }));
  }
  return rows;
}

std::vector<VariantRow> time_world_variants(Detector& detector, int repeat, int variants,
                                            const std::function<void(int)>& use) {
  std::vector<std::pair<std::string, std::unique_ptr<Sequence>>> scenes;
  const std::size_t frames = std::size_t(variants) * std::size_t(repeat + 1);
  scenes.emplace_back("World: 200-ball pile", make_crowd(200, frames));
  scenes.emplace_back("World: waving spheres 2x82k", make_crossing_spheres(144, frames, /*wave=*/true));
  std::vector<VariantRow> rows;
  for (const auto& [name, seq] : scenes) {
    DetectOptions opt;
    opt.stage = Stage::image;  // every pair drawn: the route the setting changes
    World world(detector.stage_ptr());
    std::vector<Object> objects;
    std::vector<BodyId> bodies;
    std::size_t f = 0;
    rows.push_back(time_in_turns(name, repeat, variants, use, [&] {
      seq->frame(f++, objects);
      sync_bodies(world, objects, bodies);
      const FrameResult& r = world.collide(opt);
      return std::pair(r.timings.total, r.timings.gpu_raster + r.timings.gpu_compute);
    }));
  }
  return rows;
}

Calibration calibrate(Detector& detector, const std::string& meshes_dir, const std::vector<int>& budgets, int repeat) {
  Calibration cal;
  const auto scenes = calibration_scenes(meshes_dir);
  FrameResult r;
  for (const auto& [name, objects] : scenes) {
    for (const int budget : budgets) {
      DetectOptions opt;
      opt.budget = budget;
      CalibrationRow row;
      row.scene = name;
      for (const Stage stage : {Stage::image, Stage::exact}) {
        opt.stage = stage;
        detector.detect(objects, opt, r);  // untimed: buffers grow, shapes upload
        std::vector<double> ms;
        for (int i = 0; i < repeat; ++i) {
          detector.detect(objects, opt, r);
          ms.push_back(r.timings.total - r.timings.aabb);  // the stage's part: culling is common
        }
        std::size_t candidates = 0;
        for (const PairResult& p : r.pairs) candidates += p.candidates;
        if (stage == Stage::image) {
          row.image_ms = median_of(ms);
          row.image_candidates = candidates;
          if (!r.pairs.empty()) {
            row.tile = r.pairs[0].resolution;
            // The router's count: the triangles one culling round keeps (it routes there).
            ContactCull cull;
            cull_to_contact_region(objects[0].mesh, objects[1].mesh, r.pairs[0].roi, cull, 1);
            row.triangles = cull.kept_a.size() + cull.kept_b.size();
          }
        } else {
          row.exact_ms = median_of(ms);
          row.exact_candidates = candidates;
        }
      }
      if (row.triangles > 0) cal.rows.push_back(row);
    }
  }
  const auto m = Eigen::Index(cal.rows.size());
  Eigen::MatrixXd xi(m, 3), xe(m, 2);
  Eigen::VectorXd yi(m), ye(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const CalibrationRow& row = cal.rows[std::size_t(i)];
    xi.row(i) << 1.0, double(row.triangles) * 1e-3, double(row.tile) * double(row.tile) * 1e-6;
    xe.row(i) << 1.0, double(row.triangles) * 1e-3;
    yi[i] = row.image_ms / double(row.views);
    ye[i] = row.exact_ms;
    // Relative error: a 2 s coincident copy and a 0.01 ms touch weigh the same.
    const double wi = 1.0 / std::max(yi[i], 1e-3), we = 1.0 / std::max(ye[i], 1e-3);
    xi.row(i) *= wi;
    yi[i] *= wi;
    xe.row(i) *= we;
    ye[i] *= we;
  }
  if (m > 0) {
    const Eigen::VectorXd ci = fit_nonnegative(xi, yi), ce = fit_nonnegative(xe, ye);
    cal.image = StageCost{ci[0], ci[1], ci[2]};
    cal.exact = StageCost{ce[0], ce[1], 0.0};
  }
  const StageCost in_use_image = detector.stage().router_image_cost(),
                  in_use_exact = detector.stage().router_exact_cost();
  for (const CalibrationRow& row : cal.rows) {
    const double n = double(row.triangles), texels = double(row.tile) * double(row.tile);
    const double best = std::min(row.image_ms, row.exact_ms);
    cal.best_ms += best;
    const auto score = [&](const StageCost& image, const StageCost& exact, std::size_t& wrong, double& lost) {
      const bool pick_exact = exact.predict_ms(n, 0.0) <= double(row.views) * image.predict_ms(n, texels);
      const double got = pick_exact ? row.exact_ms : row.image_ms;
      if (got > best) {
        ++wrong;
        lost += got - best;
      }
    };
    score(cal.image, cal.exact, cal.wrong_fitted, cal.lost_ms_fitted);
    score(in_use_image, in_use_exact, cal.wrong_in_use, cal.lost_ms_in_use);
  }
  return cal;
}

std::vector<LargeMeshRow> calibrate_large_meshes(Detector& detector, const std::vector<int>& stacks, int repeat) {
  std::vector<LargeMeshRow> rows;
  for (const int n : stacks) {
    LargeMeshRow row;
    row.stacks = n;
    const auto seq = make_crossing_spheres(n, std::size_t(repeat) + 1, false);
    std::vector<Object> objects;
    seq->frame(0, objects);
    for (const Object& o : objects) row.triangles += o.mesh.triangles.size();
    DetectOptions opt;  // the router
    FrameResult r;
    World world(detector.stage_ptr());
    std::vector<BodyId> bodies;
    std::vector<double> frame_ms, world_ms, narrow_ms;
    for (int f = 0; f <= repeat; ++f) {  // frame 0 untimed (trees, buffers)
      seq->frame(std::size_t(f), objects);
      detector.detect(objects, opt, r);
      if (f > 0) frame_ms.push_back(r.timings.total);
      row.frame_predicted_ms = row.kept = 0;
      for (const PairResult& p : r.pairs) {
        row.frame_predicted_ms += p.exact_stage ? p.predicted_exact_ms : p.predicted_image_ms;
        ContactCull cull;
        if (f == repeat) {
          cull_to_contact_region(objects[p.object_a].mesh, objects[p.object_b].mesh, p.roi, cull, 1);
          row.kept += cull.kept_a.size() + cull.kept_b.size();
        }
      }
      const auto t0 = Clock::now();
      sync_bodies(world, objects, bodies);
      const FrameResult& w = world.collide(opt);
      const double ms = ms_since(t0);
      if (f > 0) {
        world_ms.push_back(ms);
        narrow_ms.push_back(w.timings.cpu);
      }
      row.world_predicted_ms = 0.0;
      row.candidates = 0;
      for (const PairResult& p : w.pairs) {
        row.world_predicted_ms += p.exact_stage ? p.predicted_exact_ms : p.predicted_image_ms;
        row.candidates += p.candidates;
      }
    }
    row.frame_ms = median_of(frame_ms);
    row.world_ms = median_of(world_ms);
    row.world_narrow_ms = median_of(narrow_ms);
    rows.push_back(row);
  }
  return rows;
}

}  // namespace peelcd
