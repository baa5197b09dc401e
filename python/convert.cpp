// The Python module's conversions (python/convert.h).
#include "convert.h"

#include "peelcd/core/options.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/costs.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/scene.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace peelcd::python {


// (n, 3) float64, C-contiguous: copied with one memcpy into the library's vertices. Anything
// else is refused with what it is (no silent conversion).
std::vector<Vec3> vertices_from(const py::handle& obj, const char* what) {
  if (!py::isinstance<py::array>(obj)) throw py::type_error(std::string(what) + ": expected a numpy array of shape (n, 3)");
  const py::array arr = py::reinterpret_borrow<py::array>(obj);
  // Equal, not identical: an unpickled array's dtype is another object of the same type.
  if (!py::dtype::of<double>().attr("__eq__")(arr.dtype()).cast<bool>())
    throw py::type_error(std::string(what) + ": dtype must be float64, got " + std::string(py::str(arr.dtype())) +
                         " (use V.astype(np.float64))");
  if (arr.ndim() != 2 || arr.shape(1) != 3) {
    std::string shape;
    for (py::ssize_t i = 0; i < arr.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(arr.shape(i));
    throw py::value_error(std::string(what) + ": shape must be (n, 3), got (" + shape + ")");
  }
  if (!(arr.flags() & py::array::c_style))
    throw py::value_error(std::string(what) + ": must be C-contiguous (use np.ascontiguousarray(V))");
  std::vector<Vec3> out(std::size_t(arr.shape(0)));
  if (!out.empty()) std::memcpy(static_cast<void*>(out.data()), arr.data(), out.size() * sizeof(Vec3));
  for (std::size_t i = 0; i < out.size(); ++i)
    if (!out[i].allFinite())
      throw py::value_error(std::string(what) + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
  return out;
}

// (m, 3) of any integer dtype, C-contiguous; indices checked against `vertex_count`.
std::vector<Tri> triangles_from(const py::handle& obj, std::size_t vertex_count, const char* what) {
  if (!py::isinstance<py::array>(obj)) throw py::type_error(std::string(what) + ": expected a numpy array of shape (m, 3)");
  const py::array arr = py::reinterpret_borrow<py::array>(obj);
  if (arr.dtype().kind() != 'i' && arr.dtype().kind() != 'u')
    throw py::type_error(std::string(what) + ": dtype must be an integer type, got " + std::string(py::str(arr.dtype())));
  if (arr.ndim() != 2 || arr.shape(1) != 3) throw py::value_error(std::string(what) + ": shape must be (m, 3)");
  if (!(arr.flags() & py::array::c_style))
    throw py::value_error(std::string(what) + ": must be C-contiguous (use np.ascontiguousarray(F))");
  const py::array_t<std::int64_t> as64 = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(arr);
  const std::int64_t* p = as64.data();
  std::vector<Tri> out(std::size_t(arr.shape(0)));
  for (std::size_t t = 0; t < out.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = p[3 * t + c];
      if (v < 0 || std::uint64_t(v) >= vertex_count)
        throw py::value_error(std::string(what) + ": triangle " + std::to_string(t) + " uses vertex " + std::to_string(v) +
                              " but there are " + std::to_string(vertex_count) + " vertices");
      out[t][c] = std::uint32_t(v);
    }
  return out;
}

std::shared_ptr<const Mesh> mesh_from_arrays(const py::handle& V, const py::handle& F) {
  Mesh m;
  m.vertices = vertices_from(V, "V");
  m.triangles = triangles_from(F, m.vertices.size(), "F");
  if (m.triangles.empty()) throw py::value_error("F: a mesh needs at least one triangle");
  return std::make_shared<const Mesh>(std::move(m));
}

Eigen::Affine3d pose_from(const py::handle& obj) {
  if (obj.is_none()) return Eigen::Affine3d::Identity();
  const py::array_t<double, py::array::c_style | py::array::forcecast> a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) throw py::value_error("pose: expected a 4x4 matrix");
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = a.at(r, c);
  if (!m.allFinite()) throw py::value_error("pose: has a NaN or infinite entry");
  if (m.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) throw py::value_error("pose: the last row must be [0, 0, 0, 1]");
  Eigen::Affine3d pose;
  pose.matrix() = m;
  if (const std::string problem = pose_problem(pose); !problem.empty()) throw py::value_error("pose: " + problem);
  return pose;
}

// Keyword options, named as in scene files (theta, stage, self, volume, ...), checked as there.
DetectOptions options_from(const py::dict& kwargs) {
  DetectOptions o;
  for (const auto& [k, v] : kwargs) {
    const std::string key = py::str(k);
    const OptionSpec* spec = find_option(key);
    if (!spec) throw py::type_error("unknown option '" + key + "' (the scene files' keys: docs/python.md)");
    OptionValue value;
    if (py::isinstance<py::bool_>(v)) value = v.cast<bool>();
    else if (py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v)) value = v.cast<double>();
    else if (py::isinstance<py::str>(v)) value = v.cast<std::string>();
    else throw py::type_error("option '" + key + "': expected a bool, a number or a string");
    try {
      set_option(o, *spec, value, "option '" + key + "'");
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
  }
  return o;
}

// The GL stage's settings from keywords (gl_option_table(): peeler, resolve, batch, gpu_select, gpu_filter, coverage);
// refused on the CPU stage, which has none.
gl::GlOptions gl_options_from(const std::string& backend, const py::kwargs& kwargs) {
  gl::GlOptions o;
  for (const auto& [k, v] : kwargs) {
    const std::string key = py::str(k);
    if (key == "costs") continue;  // the router's models (costs_from())
    if (backend == "cpu")
      throw py::value_error("GL option '" + key + "': the cpu backend has no GL stage (use osmesa or egl)");
    std::string words;
    if (py::isinstance<py::bool_>(v)) words = v.cast<bool>() ? "true" : "false";
    else if (py::isinstance<py::str>(v)) words = v.cast<std::string>();
    else throw py::type_error("GL option '" + key + "': expected a bool or a string");
    const std::string problem = gl::set_gl_option(o, key, words);
    if (problem.rfind("unknown GL option", 0) == 0)
      throw py::type_error(problem + " (GL options: peeler, resolve, batch, gpu_select, gpu_filter, coverage)");
    if (!problem.empty()) throw py::value_error("GL option " + problem);
  }
  return o;
}

// `costs=FILE` among a constructor's keywords, as a path (str or os.PathLike), or empty.
std::string costs_from(const py::kwargs& kwargs) {
  if (!kwargs.contains("costs") || kwargs["costs"].is_none()) return {};
  return py::str(py::module_::import("os").attr("fspath")(kwargs["costs"]));
}

// The stage of `backend` with the GL settings `gl` and the router's models from `costs` (a file
// written by peelcd calibrate --write-costs), else $PEELCD_COSTS's, else the built-in ones.
std::shared_ptr<ImageStage> stage_for(const std::string& backend, const gl::GlOptions& gl,
                                      const std::string& costs) {
  try {
    std::shared_ptr<ImageStage> stage = make_image_stage(backend, gl);
    if (!costs.empty()) apply_cost_models(*stage, costs);
    else apply_cost_models_from_env(*stage);
    return stage;
  } catch (const InputError& e) {
    throw py::value_error(e.what());
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("peelcd: backend '") + backend + "' could not start: " + e.what());
  }
}

// A body from Python: the id add_rigid / add_deforming returned, or the name it was given (an
// unknown one is named).
BodyId body_of(const World& world, const py::handle& body) {
  if (py::isinstance<py::str>(body)) {
    const std::string name = body.cast<std::string>();
    if (const std::optional<BodyId> id = world.find(name)) return *id;
    throw py::value_error("body '" + name + "': no body has this name");
  }
  if (!py::isinstance<py::int_>(body) || py::isinstance<py::bool_>(body))
    throw py::type_error("body: expected the id add_rigid or add_deforming returned (an int) or a body's name (a str)");
  const long long id = body.cast<long long>();
  if (id < 0 || id > 0xffffffffLL)
    throw py::value_error("body " + std::to_string(id) + ": no such body (a body is what add_rigid or add_deforming returned)");
  return BodyId(id);
}

// One pair of a result, as NumPy arrays.
// `name_of(i)`: object or body i's name, as given ("" when none was).
py::dict pair_dict(const PairResult& p, const std::function<std::string(std::size_t)>& name_of) {
  const std::size_t k = p.colliding.size();
  py::array_t<std::uint32_t> tris({py::ssize_t(k), py::ssize_t(2)});
  py::array_t<double> seg({py::ssize_t(k), py::ssize_t(2), py::ssize_t(3)});
  py::list kinds;
  auto t = tris.mutable_unchecked<2>();
  auto s = seg.mutable_unchecked<3>();
  for (std::size_t i = 0; i < k; ++i) {
    const Contact& c = p.colliding[i];
    t(i, 0) = c.tri_a;
    t(i, 1) = c.tri_b;
    const double nan = std::numeric_limits<double>::quiet_NaN();  // no segment asked for (contacts="pairs")
    for (int d = 0; d < 3; ++d) {
      s(i, 0, d) = c.classified() ? c.p[d] : nan;
      s(i, 1, d) = c.classified() ? c.q[d] : nan;
    }
    kinds.append(to_string(c.kind));
  }
  py::dict d;
  d["a"] = p.object_a;
  d["b"] = p.object_b;
  d["name_a"] = name_of(p.object_a);
  d["name_b"] = name_of(p.object_b);
  d["colliding"] = tris;  // as C++'s PairResult::colliding and the JSON's "colliding"
  d["triangles"] = tris;  // the same array under its 0.2 name, kept for the 0.3 release
  d["kinds"] = kinds;
  d["segments"] = seg;
  d["relation"] = to_string(p.relation);
  d["relation_note"] = p.relation_note;
  d["is_collision"] = p.is_collision();
  // As the JSON result says it: exact, image, or none (culled before any view was drawn).
  d["stage"] = p.exact_stage ? "exact" : std::strcmp(pair_path(p), "none") == 0 ? "none" : "image";
  d["path"] = pair_path(p);
  d["margin_fallback"] = p.margin_fallback;  // the exact path, the margin being too wide for the image stage
  d["candidates"] = p.candidates;
  if (p.volume.known) {
    d["volume"] = p.volume.volume;
    d["volume_error"] = p.volume.error;
    d["volume_gradient"] = py::array_t<double>(3, p.volume.gradient.data());
  } else {
    d["volume"] = py::none();
    if (!p.volume.reason.empty()) d["volume_unknown"] = p.volume.reason;
  }
  if (!p.near.pairs.empty()) {  // the margin option: triangle pairs within it
    const std::size_t k = p.near.pairs.size();
    py::array_t<std::uint32_t> tri({k, std::size_t(2)});
    py::array_t<double> dist(k);
    auto t = tri.mutable_unchecked<2>();
    auto dd = dist.mutable_unchecked<1>();
    for (std::size_t i = 0; i < k; ++i) {
      t(i, 0) = p.near.pairs[i].tri_a;
      t(i, 1) = p.near.pairs[i].tri_b;
      dd(i) = p.near.pairs[i].distance;
    }
    d["near_triangles"] = tri;
    d["near_distances"] = dist;
    d["distance"] = p.near.distance;
    d["witness_a"] = py::array_t<double>(3, p.near.p.data());
    d["witness_b"] = py::array_t<double>(3, p.near.q.data());
  } else {
    d["distance"] = py::none();
  }
  if (p.depth.known) {  // the depth option: move A by depth * depth_direction to separate
    d["depth"] = p.depth.depth;
    d["depth_direction"] = py::array_t<double>(3, p.depth.direction.data());
    d["depth_bound"] = p.depth.bound;
  } else {
    d["depth"] = py::none();
    if (!p.depth.reason.empty()) d["depth_unknown"] = p.depth.reason;
  }
  return d;
}

py::dict result_dict(const FrameResult& r, const std::function<std::string(std::size_t)>& name_of,
                     const std::optional<gl::GlOptions>& gl) {
  py::list pairs;
  bool any = false;
  for (const PairResult& p : r.pairs) {
    pairs.append(pair_dict(p, name_of));
    any = any || p.is_collision();
  }
  py::dict d;
  d["pairs"] = pairs;
  d["is_collision"] = any;
  d["total_ms"] = r.timings.total;
  if (gl) {  // the GL stage's settings of the run
    py::dict g;
    for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
      const std::string v = spec.get(*gl);
      if (*spec.choices) g[spec.key] = v;
      else g[spec.key] = v == "true";
    }
    d["gl_options"] = g;
  }
  return d;
}

// A peelcd.Mesh, or any object with .vertices (n, 3) and .faces (m, 3) arrays (a trimesh.Trimesh,
// an Open3D-like mesh through NumPy): the arrays are read as Mesh(V, F) reads them.
PyMesh as_mesh(const py::handle& obj, const std::string& where) {
  if (py::isinstance<PyMesh>(obj)) return obj.cast<PyMesh>();
  if (py::hasattr(obj, "vertices") && py::hasattr(obj, "faces")) {
    const py::module_ np = py::module_::import("numpy");
    return PyMesh{mesh_from_arrays(np.attr("asarray")(obj.attr("vertices")), np.attr("asarray")(obj.attr("faces")))};
  }
  throw py::type_error(where + ": expected a peelcd.Mesh or an object with .vertices and .faces arrays (e.g. a "
                       "trimesh.Trimesh), got " + std::string(py::str(py::type::of(obj).attr("__name__"))));
}


}  // namespace peelcd::python
