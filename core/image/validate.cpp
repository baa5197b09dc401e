// The checks of a frame's input: objects (finite coordinates, indices in range, IDs that fit),
// poses and options, each failure naming the input and the problem.
#include "peelcd/core/image/detector.h"
#include "peelcd/core/options.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace peelcd {
namespace {

std::string object_label(const Object& o, std::size_t i) {
  return "object " + std::to_string(i) + (o.name.empty() ? "" : " '" + o.name + "'");
}

}  // namespace

void validate_objects(const std::vector<Object>& objects, bool float_range) {
  for (std::size_t i = 0; i < objects.size(); ++i) validate_object(objects[i], i, float_range);
}

void validate_objects(const std::vector<const Object*>& objects, bool float_range) {
  for (std::size_t i = 0; i < objects.size(); ++i) validate_object(*objects[i], i, float_range);
}

std::string pose_problem(const Eigen::Affine3d& pose) {
  if (!pose.matrix().allFinite()) return "has a NaN or infinite entry";
  const double det = pose.linear().determinant();
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    return "is singular (its rotation/scale part has determinant " + std::to_string(det) +
           ": a zero scale collapses the mesh)";
  return {};
}

std::string coordinate_problem(const Vec3& p, bool float_range) {
  if (!p.allFinite()) return "has a NaN or infinite coordinate";
  if (float_range && p.cwiseAbs().maxCoeff() > kFloatMax) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "(%g, %g, %g) is outside the float range (|x| <= 3.4e38) the image stage works in",
                  p.x(), p.y(), p.z());
    return buf;
  }
  return {};
}

namespace {
// The checks, the object's label built only on failure (a valid frame allocates nothing).
template <class Label>
void check_object(const Object& o, const Label& label, bool float_range) {
  const Mesh& m = o.mesh;
  const auto fail = [&](const std::string& problem) { throw std::invalid_argument("peelcd: " + label() + problem); };
  for (std::size_t v = 0; v < m.vertices.size(); ++v)
    if (!m.vertices[v].allFinite() || (float_range && m.vertices[v].cwiseAbs().maxCoeff() > kFloatMax))
      fail(": vertex " + std::to_string(v) + " " + coordinate_problem(m.vertices[v], float_range));
  const std::size_t n = m.vertices.size();
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (std::uint32_t v : m.triangles[f])
      if (v >= n)
        fail(": triangle " + std::to_string(f) + " uses vertex " + std::to_string(v) + " but the mesh has " +
             std::to_string(n) + " vertices");
  // A layer texel stores object << 31 | ID + 1: IDs must stay below 2^31 - 1.
  if (std::max(m.triangles.size(), m.vertices.size()) >= 0x7fffffffu)
    fail(" has 2^31 - 1 or more triangles or vertices; IDs hold 31 bits");
  if (o.rigid) {
    if (!o.rigid->shape) fail(": rigid motion without a shape");
    if (o.rigid->shape->triangles.size() != m.triangles.size())
      fail(": its rigid shape has " + std::to_string(o.rigid->shape->triangles.size()) + " triangles, its world mesh " +
           std::to_string(m.triangles.size()));
    if (const std::string problem = pose_problem(o.rigid->pose); !problem.empty()) fail(": its pose " + problem);
  }
}
}  // namespace

void validate_object(const Object& o, std::size_t i, bool float_range) {
  check_object(o, [&] { return object_label(o, i); }, float_range);
}

void validate_object(const Object& o, const std::string& label, bool float_range) {
  check_object(o, [&] { return label; }, float_range);
}

void validate_options(const DetectOptions& opt, int max_resolution) {
  const char* where = "peelcd: options: ";
  // Every option's range, from the one table (peelcd/core/options.h).
  for (const OptionSpec& spec : option_table())
    if (const std::string problem = check_option(spec, spec.get(opt)); !problem.empty())
      throw std::invalid_argument(std::string(where) + spec.key + " " + problem);
  // And what depends on the stage: its largest view.
  if (opt.resolution > max_resolution)
    throw std::invalid_argument(std::string(where) + "resolution " + std::to_string(opt.resolution) + " is outside 1.." +
                                std::to_string(max_resolution) +
                                " (the image stage's largest view: GL_MAX_TEXTURE_SIZE on GL; 0 = share the budget)");
  if (opt.resolution == 0 && opt.budget > max_resolution)
    throw std::invalid_argument(std::string(where) + "budget " + std::to_string(opt.budget) + " is outside 1.." +
                                std::to_string(max_resolution) + " (the image stage's largest view)");
}

}  // namespace peelcd
