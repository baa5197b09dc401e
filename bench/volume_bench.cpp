#include "peelcd/bench/volume_bench.h"

#include "peelcd/bench/suite.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/relation.h"

#include <chrono>
#include <cstdio>

namespace peelcd::bench {

std::string run_volume_suite(const VolumeSuite& suite) {
  using Clock = std::chrono::steady_clock;
  const auto ms_since = [](Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); };
  const std::size_t frames = std::max<std::size_t>(1, suite.frames);
  const int s = std::max(3, suite.stacks);
  const Mesh base_a = make_uv_sphere(Vec3(0, 0, 0), 1.0, s, 2 * s);
  const Mesh base_b = make_uv_sphere(Vec3(0, 0, 0), 0.8, s, 2 * s);
  std::vector<Mesh> as, bs;
  for (std::size_t f = 0; f < frames; ++f) {
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translate(Vec3(0.9, 0.2, 0.1));
    pose.rotate(Eigen::AngleAxisd(0.05 * double(f + 1), Vec3(1, 2, 3).normalized()));
    Mesh b = base_b;
    for (Vec3& v : b.vertices) v = pose * v;
    as.push_back(base_a);
    bs.push_back(std::move(b));
  }
  std::printf("peelcd bench: volume (two closed UV spheres of %zu triangles each, overlapping deeply; %zu frames); "
              "median ms per frame, one thread\n",
              base_a.triangles.size(), frames);
  std::printf("%-44s %10s %8s %14s %12s\n", "method", "median ms", "ratio", "volume", "rel. error");
  std::string csv = "method,frame,ms,volume,exact\n";
  std::vector<double> exact(frames), cgal_ms;
  for (std::size_t f = 0; f < frames; ++f) {
    const auto t0 = Clock::now();
    exact[f] = exact_overlap_volume(as[f], bs[f]);
    cgal_ms.push_back(ms_since(t0));
    csv += "CGAL corefinement + volume," + std::to_string(f) + "," + std::to_string(cgal_ms.back()) + "," +
           std::to_string(exact[f]) + "," + std::to_string(exact[f]) + "\n";
  }
  const double cgal = median(cgal_ms);
  for (const int n : {kVolumeResolution, 2 * kVolumeResolution}) {
    std::vector<double> ms;
    double worst = 0.0, last = 0.0;
    for (std::size_t f = 0; f < frames; ++f) {
      const auto t0 = Clock::now();
      const VolumeEstimate e = overlap_volume(as[f], bs[f], intersection(bounds(as[f]), bounds(bs[f])), n);
      ms.push_back(ms_since(t0));
      last = e.volume;
      worst = std::max(worst, std::abs(e.volume - exact[f]) / exact[f]);
      csv += "peelcd " + std::to_string(n) + "," + std::to_string(f) + "," + std::to_string(ms.back()) + "," +
             std::to_string(e.volume) + "," + std::to_string(exact[f]) + "\n";
    }
    const std::string name = "peelcd image-space volume, " + std::to_string(n) + " rays per axis";
    std::printf("%-44s %10.2f %8.3f %14.6f %11.4f%%\n", name.c_str(), median(ms), median(ms) / cgal, last, 100.0 * worst);
  }
  std::printf("%-44s %10.2f %8.3f %14.6f %12s\n", "CGAL corefinement (exact) + volume()", cgal, 1.0, exact.back(), "(reference)");
  std::printf("(ratio: to CGAL. rel. error: the worst frame's. peelcd's time includes its closedness and orientation "
              "checks and the error estimate: rays along x, y, z and z at half the resolution.)\n");
  return csv;
}

}  // namespace peelcd::bench
