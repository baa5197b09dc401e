#include "peelcd/bench/volume_bench.h"
#include "peelcd/core/clock.h"

#include "peelcd/bench/suite.h"
#include "peelcd/core/frame.h"
#include "peelcd/core/primitives.h"
#include "peelcd/core/exact/relation.h"

#include <chrono>
#include <cstdio>
#include <random>

namespace peelcd::bench {

namespace {

// B scaled to 0.6 of A's box diagonal, turned at random and put at random within a quarter of A's
// diagonal of A's centre (the same poses on every machine for one seed of `rng`).
Mesh random_pose(const Mesh& a, const Mesh& b, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Aabb ba = bounds(a), bb = bounds(b);
  const double size_a = (ba.hi - ba.lo).norm(), size_b = (bb.hi - bb.lo).norm();
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  double r[7];  // drawn in order (a constructor's arguments are evaluated in no fixed order)
  for (double& x : r) x = u(rng);
  pose.translate(0.5 * (ba.lo + ba.hi) + 0.25 * size_a * Vec3(r[0], r[1], r[2]));
  pose.rotate(Eigen::AngleAxisd(3.14159265358979 * r[3], Vec3(r[4], r[5], r[6]).normalized()));
  pose.scale(0.6 * size_a / size_b);
  pose.translate(-0.5 * (bb.lo + bb.hi));
  Mesh m = b;
  for (Vec3& v : m.vertices) v = pose * v;
  return m;
}

// Per mesh pair: frames with a non-zero exact volume, the worst |estimate - exact| / error
// estimate (<= 1: the estimate held), how many frames it did not hold, the median relative error.
void print_coverage(const VolumeSuite& suite) {
  std::printf("\nthe error estimate against CGAL's exact volume: %zu random poses per pair (B scaled to 0.6 of A's "
              "size), %d rays per axis\n",
              suite.coverage_frames, kVolumeResolution);
  std::printf("%-34s %7s %16s %10s %18s %16s\n", "pair", "frames", "worst |err|/est", "not held", "median rel. error",
              "median est./vol.");
  std::mt19937 rng(2007);
  const auto& ms = suite.coverage_meshes;
  std::size_t all = 0, failed = 0;
  double worst_all = 0.0;
  for (std::size_t i = 0; i + 1 < ms.size(); ++i) {
    std::vector<double> rel, est;
    double worst = 0.0;
    std::size_t counted = 0, not_held = 0;
    for (std::size_t f = 0; f < suite.coverage_frames; ++f) {
      const Mesh& a = ms[i].second;
      const Mesh b = random_pose(a, ms[i + 1].second, rng);
      double exact = 0.0;
      try {
        exact = exact_overlap_volume(a, b);
      } catch (const std::exception&) {
        continue;  // CGAL refused the pose (a degenerate intersection): no reference
      }
      const VolumeEstimate e = overlap_volume(a, b, intersection(bounds(a), bounds(b)), kVolumeResolution);
      if (exact <= 0.0 && e.volume <= 0.0) continue;
      const double err = std::abs(e.volume - exact);
      const double ratio = e.error > 0.0 ? err / e.error : (err > 0.0 ? 1e300 : 0.0);
      worst = std::max(worst, ratio);
      not_held += ratio > 1.0 ? 1 : 0;
      rel.push_back(exact > 0.0 ? err / exact : 0.0);
      est.push_back(exact > 0.0 ? e.error / exact : 0.0);
      ++counted;
    }
    const std::string name = ms[i].first + " x " + ms[i + 1].first;
    std::printf("%-34s %7zu %16.3f %10zu %17.2e %16.2e\n", name.c_str(), counted, worst, not_held,
                rel.empty() ? 0.0 : median(rel), est.empty() ? 0.0 : median(est));
    all += counted;
    failed += not_held;
    worst_all = std::max(worst_all, worst);
  }
  std::printf("all: %zu frames, worst |err|/est %.3f, %zu not held (the estimate: %.0fx the largest difference of "
              "the x, y and half-resolution casts to z, at least one texel column)\n",
              all, worst_all, failed, kVolumeErrorFactor);
}

}  // namespace

std::string run_volume_suite(const VolumeSuite& suite) {
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
  if (suite.coverage_meshes.size() >= 2 && suite.coverage_frames > 0) print_coverage(suite);
  return csv;
}

}  // namespace peelcd::bench
