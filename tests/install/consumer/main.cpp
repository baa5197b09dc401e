// A consumer that includes only the umbrella header: a World on the image stage a backend names
// (make_image_stage), a frame, the pairs. Built by tests/install/test_install.cmake through
// pkg-config with -std=c++20 and through find_package(peelcd COMPONENTS ...).
#include <peelcd/peelcd.h>

#include <cstdio>
#include <memory>

int main(int argc, char** argv) {
  const char* backend = argc > 1 ? argv[1] : "cpu";
  peelcd::World world(peelcd::make_image_stage(backend));
  const auto a = std::make_shared<const peelcd::Mesh>(peelcd::make_uv_sphere(peelcd::Vec3(0, 0, 0), 1.0, 12, 24));
  const auto b = std::make_shared<const peelcd::Mesh>(peelcd::make_uv_sphere(peelcd::Vec3(1.2, 0.2, 0.1), 0.8, 12, 24));
  world.add_rigid(a, Eigen::Affine3d::Identity(), "a");
  world.add_rigid(b, Eigen::Affine3d::Identity(), "b");
  peelcd::DetectOptions options;
  options.stage = peelcd::Stage::image;
  const peelcd::FrameResult& r = world.collide(options);
  if (r.pairs.size() != 1 || r.pairs[0].colliding.empty()) {
    std::fprintf(stderr, "consumer: expected one colliding pair on %s\n", backend);
    return 1;
  }
  std::printf("consumer: %s (%s): %zu contacts\n", backend, world.stage().renderer().c_str(), r.pairs[0].colliding.size());
  return 0;
}
