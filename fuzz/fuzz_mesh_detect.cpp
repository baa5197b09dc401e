// Fuzzes mesh loading plus one frame of detection: the input's first byte picks the format
// (OBJ, PLY, STL, OFF), the rest is the file. A mesh that loads is fitted into [-1, 1]^3 and
// collided with a sphere on OSMesa at 32^2. Every input must end in a result or an InputError.
#include "peelcd/core/primitives.h"
#include "peelcd/gl/pipeline.h"
#include "peelcd/gl_osmesa/osmesa_context.h"
#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"

#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <string>

namespace {
peelcd::gl::Pipeline& pipeline() {
  static peelcd::gl::Pipeline p(std::make_shared<peelcd::gl::OsmesaContext>());
  return p;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const ext[] = {".obj", ".ply", ".stl", ".off"};
  const std::string path = "/tmp/peelcd_fuzz_" + std::to_string(getpid()) + ext[data[0] % 4];
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  peelcd::Mesh mesh;
  try {
    mesh = peelcd::load_mesh(path);
    peelcd::validate_mesh(mesh, path);
  } catch (const peelcd::InputError&) {
    return 0;
  } catch (const std::invalid_argument&) {
    return 0;
  }
  if (mesh.triangles.size() > 20000) return 0;  // keep each run short
  const peelcd::Aabb box = peelcd::bounds(mesh);
  const double extent = box.extent().maxCoeff();
  for (peelcd::Vec3& p : mesh.vertices) p = extent > 0 ? peelcd::Vec3((p - box.center()) * (2.0 / extent)) : peelcd::Vec3(p - box.center());
  peelcd::DetectOptions opt;
  opt.resolution = 32;
  opt.views = 1;
  pipeline().detect({{"fuzz", mesh}, {"sphere", peelcd::make_uv_sphere(peelcd::Vec3(0, 0, 0), 0.8, 8, 16)}}, opt);
  return 0;
}
