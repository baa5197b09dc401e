// peelcd's Python module (import peelcd): meshes from NumPy arrays or files, persistent worlds of
// rigid and deforming bodies, one-shot frames, results as NumPy arrays (docs/python.md).
// Options are the scene files' keys with the same checks (peelcd/core/options.h); errors are
// Python exceptions carrying the library's messages (ValueError for bad input, RuntimeError for
// a backend that cannot start); the GIL is released while a frame runs.
#include "peelcd/backends.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exclusive_use.h"
#include "peelcd/core/options.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/core/world/world.h"
#include "peelcd/eval/classes.h"
#include "peelcd/io/costs.h"
#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/scene.h"
#include "peelcd/version.h"

#include <pybind11/numpy.h>
#include <functional>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>

namespace py = pybind11;
using namespace peelcd;

namespace {

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

// The GL stage's settings from keywords (gl_option_table(): peeler, resolve, batch, gpu_select);
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
      throw py::type_error(problem + " (GL options: peeler, resolve, batch, gpu_select)");
    if (!problem.empty()) throw py::value_error("GL option " + problem);
  }
  return o;
}

// The stage of `backend` with the GL settings `gl` and the router's models from `costs` (a file
// written by peelcd calibrate --write-costs), else $PEELCD_COSTS's, else the built-in ones.
// `costs=FILE` among a constructor's keywords, as a path (str or os.PathLike), or empty.
std::string costs_from(const py::kwargs& kwargs) {
  if (!kwargs.contains("costs") || kwargs["costs"].is_none()) return {};
  return py::str(py::module_::import("os").attr("fspath")(kwargs["costs"]));
}

std::shared_ptr<ImageStage> stage_for(const std::string& backend, const gl::GlOptions& gl = {},
                                      const std::string& costs = {}) {
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
    for (int d = 0; d < 3; ++d) {
      s(i, 0, d) = c.p[d];
      s(i, 1, d) = c.q[d];
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
                     const std::optional<gl::GlOptions>& gl = std::nullopt) {
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

template <class Fn>
auto translate_errors(Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  } catch (const InputError& e) {
    throw py::value_error(e.what());
  }
}

// A persistent world (peelcd::World) with its own image stage.
struct PyWorld {
  PyWorld(const std::string& backend, const gl::GlOptions& o, const std::string& costs)
      : world(backend == "cpu" && costs.empty() && !std::getenv("PEELCD_COSTS") ? nullptr : stage_for(backend, o, costs)) {
    if (backend != "cpu") gl = o;
  }
  World world;
  std::optional<gl::GlOptions> gl;  // the GL stage's settings (none on the CPU stage)
  // The thread inside a method, conversion of its result included: a second thread is refused
  // (RuntimeError) before it reaches the World, and a result is converted from the caller's own
  // FrameResult, never from one the next frame rewrites.
  std::atomic<std::thread::id> owner{};
};

// The frame API on meshes given each call (peelcd::Detector).
struct PyDetector {
  PyDetector(const std::string& backend, const gl::GlOptions& o, const std::string& costs)
      : detector(stage_for(backend, o, costs)) {
    if (backend != "cpu") gl = o;
  }
  Detector detector;
  std::optional<gl::GlOptions> gl;
  std::atomic<std::thread::id> owner{};  // as PyWorld's
};

struct PyMesh {
  std::shared_ptr<const Mesh> mesh;
};

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

}  // namespace

namespace {

// Meshes: the Mesh class, load_mesh() and load_scene().
void bind_meshes(py::module_& m) {
  py::class_<PyMesh>(m, "Mesh", "A triangle mesh: vertices V (n, 3) float64, triangles F (m, 3) integers")
      .def(py::init([](const py::handle& V, const py::handle& F) { return PyMesh{mesh_from_arrays(V, F)}; }), py::arg("V"),
           py::arg("F"))
      .def_property_readonly("V", [](const PyMesh& self) {
        py::array_t<double> a({py::ssize_t(self.mesh->vertices.size()), py::ssize_t(3)});
        if (!self.mesh->vertices.empty()) std::memcpy(a.mutable_data(), self.mesh->vertices.data(), a.nbytes());
        return a;
      })
      .def_property_readonly("F", [](const PyMesh& self) {
        py::array_t<std::uint32_t> a({py::ssize_t(self.mesh->triangles.size()), py::ssize_t(3)});
        if (!self.mesh->triangles.empty()) std::memcpy(a.mutable_data(), self.mesh->triangles.data(), a.nbytes());
        return a;
      })
      .def(py::pickle(  // pickle, copy.deepcopy, multiprocessing: the arrays V and F
          [](const PyMesh& self) {
            py::array_t<double> V({py::ssize_t(self.mesh->vertices.size()), py::ssize_t(3)});
            if (!self.mesh->vertices.empty()) std::memcpy(V.mutable_data(), self.mesh->vertices.data(), V.nbytes());
            py::array_t<std::uint32_t> F({py::ssize_t(self.mesh->triangles.size()), py::ssize_t(3)});
            if (!self.mesh->triangles.empty()) std::memcpy(F.mutable_data(), self.mesh->triangles.data(), F.nbytes());
            return py::make_tuple(V, F);
          },
          [](const py::tuple& t) {
            if (t.size() != 2) throw std::runtime_error("peelcd.Mesh: a pickled mesh is (V, F)");
            return PyMesh{mesh_from_arrays(t[0], t[1])};
          }))
      .def("__repr__", [](const PyMesh& self) {
        return "<peelcd.Mesh " + std::to_string(self.mesh->vertices.size()) + " vertices, " +
               std::to_string(self.mesh->triangles.size()) + " triangles>";
      });

  m.def("load_mesh", [](const std::string& path) {
    py::gil_scoped_release release;  // a large file takes seconds: other Python threads run meanwhile
    return translate_errors([&] {
      if (is_node_scene(path)) {  // several nodes would be merged into one mesh: said, not done
        const std::size_t nodes = load_objects(scene_from_meshes({path})).size();
        if (nodes > 1)
          throw InputError("'" + path + "' is a glTF scene of " + std::to_string(nodes) +
                           " mesh nodes: peelcd.load_scene(path) gives one object per node");
      }
      Mesh mesh = load_mesh(path);
      validate_mesh(mesh, "'" + path + "'");
      return PyMesh{std::make_shared<const Mesh>(std::move(mesh))};
    });
  }, py::arg("path"), "Loads a mesh file (OBJ, PLY, STL, OFF, glTF, ...) as the command line does");

  m.def("load_scene", [](const std::string& path) {
    return translate_errors([&] {
      // A glTF / GLB file is a scene of nodes, one object each (as the command line takes it).
      std::vector<Object> objects;
      {
        py::gil_scoped_release release;
        const Scene scene = is_node_scene(path) ? scene_from_meshes({path}) : load_scene(path);
        objects = load_objects(scene);
      }
      py::list out;
      for (Object& o : objects) {
        py::dict d;
        d["name"] = o.name;
        d["mesh"] = PyMesh{std::make_shared<const Mesh>(std::move(o.mesh))};
        d["self"] = o.self;
        out.append(d);
      }
      return out;
    });
  }, py::arg("path"),
        "A scene file's (or a glTF / GLB file's: one per mesh node) objects in world space: a list of dicts with "
        "name, mesh and self");
}

// The World: persistent bodies. Every method holds the PyWorld's guard for its whole run, the
// conversion of its result included (a second thread: RuntimeError); the GIL is released while
// peelcd works without Python objects (a tree's build, a frame).
void bind_world(py::module_& m) {
  constexpr const char* kWorld = "peelcd::World";
  py::class_<PyWorld>(m, "World", "Persistent bodies kept across frames (peelcd::World): rigid ones move by their pose, "
                                  "deforming ones by their vertices")
      .def(py::init([](const std::string& backend, const py::kwargs& kwargs) {
             return std::make_unique<PyWorld>(backend, gl_options_from(backend, kwargs), costs_from(kwargs));
           }),
           py::arg("backend") = "cpu",
           "backend: cpu, osmesa or egl; GL backends take the GL options as keywords (peeler, resolve, batch, gpu_select); "
           "costs=FILE: the router's cost models (peelcd calibrate --write-costs; default $PEELCD_COSTS)")
      .def("add_rigid", [](PyWorld& w, const py::handle& m, const py::object& pose, const std::string& name, bool self) {
        const ExclusiveUse guard(w.owner, kWorld);
        const PyMesh mesh = as_mesh(m, "mesh");
        const Eigen::Affine3d p = pose_from(pose);
        py::gil_scoped_release release;
        return translate_errors([&] {
          const BodyId id = w.world.add_rigid(mesh.mesh, p, name);
          w.world.set_self(id, self);
          return id;
        });
      }, py::arg("mesh"), py::arg("pose") = py::none(), py::arg("name") = "", py::arg("self_collision") = false)
      .def("add_deforming", [](PyWorld& w, const py::handle& m, const std::string& name, bool self) {
        const ExclusiveUse guard(w.owner, kWorld);
        const PyMesh mesh = as_mesh(m, "mesh");
        py::gil_scoped_release release;
        return translate_errors([&] {
          const BodyId id = w.world.add_deforming(*mesh.mesh, name);
          w.world.set_self(id, self);
          return id;
        });
      }, py::arg("mesh"), py::arg("name") = "", py::arg("self_collision") = false)
      .def("set_pose", [](PyWorld& w, const py::handle& body, const py::object& pose) {
        const ExclusiveUse guard(w.owner, kWorld);
        const BodyId id = body_of(w.world, body);
        translate_errors([&] { w.world.set_pose(id, pose_from(pose)); });
      }, py::arg("body"), py::arg("pose"), "body: its id or its name; pose: 4x4")
      .def("set_vertices", [](PyWorld& w, const py::handle& body, const py::handle& V) {
        const ExclusiveUse guard(w.owner, kWorld);
        const BodyId id = body_of(w.world, body);
        std::vector<Vec3> v = vertices_from(V, "V");
        py::gil_scoped_release release;
        translate_errors([&] { w.world.set_vertices(id, std::move(v)); });
      }, py::arg("body"), py::arg("V"))
      .def("set_mesh", [](PyWorld& w, const py::handle& body, const py::handle& m) {
        const ExclusiveUse guard(w.owner, kWorld);
        const PyMesh mesh = as_mesh(m, "mesh");
        const BodyId id = body_of(w.world, body);
        py::gil_scoped_release release;
        translate_errors([&] { w.world.set_mesh(id, *mesh.mesh); });
      }, py::arg("body"), py::arg("mesh"), "A new mesh (topology) for the body: fracture, remeshing")
      .def("set_self", [](PyWorld& w, const py::handle& body, bool self) {
        const ExclusiveUse guard(w.owner, kWorld);
        translate_errors([&] { w.world.set_self(body_of(w.world, body), self); });
      }, py::arg("body"), py::arg("on"))
      .def("remove", [](PyWorld& w, const py::handle& body) {
        const ExclusiveUse guard(w.owner, kWorld);
        translate_errors([&] { w.world.remove(body_of(w.world, body)); });
      }, py::arg("body"))
      .def("find", [](PyWorld& w, const std::string& name) -> py::object {
        const ExclusiveUse guard(w.owner, kWorld);
        const std::optional<BodyId> id = w.world.find(name);
        return id ? py::object(py::int_(*id)) : py::object(py::none());
      }, py::arg("name"), "The id of the body named `name`, or None")
      .def("__len__", [](PyWorld& w) {
        const ExclusiveUse guard(w.owner, kWorld);
        return w.world.size();
      })
      // Options as one dict (the Python class World.collide(**options) passes them): a keyword
      // named `self` cannot clash with the bound instance.
      .def("_collide", [](PyWorld& w, const py::dict& options) {
        const ExclusiveUse guard(w.owner, kWorld);
        const DetectOptions opt = options_from(options);
        FrameResult r;  // the caller's own: converted below while no other thread can enter
        {
          py::gil_scoped_release release;
          translate_errors([&] { w.world.collide(opt, r); });
        }
        return result_dict(r, [&](std::size_t i) { return w.world.name(BodyId(i)); }, w.gl);
      }, py::arg("options"), "One frame (World.collide(**options) is the documented entry)");
}

// The frame API: the Detector.
void bind_detector(py::module_& m) {
  py::class_<PyDetector>(m, "Detector", "The frame API (peelcd::Detector): the objects given whole each frame")
      .def(py::init([](const std::string& backend, const py::kwargs& kwargs) {
             return std::make_unique<PyDetector>(backend, gl_options_from(backend, kwargs), costs_from(kwargs));
           }),
           py::arg("backend") = "cpu",
           "backend: cpu, osmesa or egl; GL backends take the GL options as keywords (peeler, resolve, batch, gpu_select); "
           "costs=FILE: the router's cost models (peelcd calibrate --write-costs; default $PEELCD_COSTS)")
      .def("_detect", [](PyDetector& d, const py::list& objects, const py::dict& options) {
        const ExclusiveUse guard(d.owner, "peelcd::Detector");
        const DetectOptions opt = options_from(options);
        std::vector<Object> objs;
        for (const py::handle& h : objects) {
          Object o;
          const std::string where = "objects[" + std::to_string(objs.size()) + "]";
          if (py::isinstance<py::dict>(h)) {  // the scene files' object keys, nothing else
            const py::dict dd = py::reinterpret_borrow<py::dict>(h);
            for (const auto& [k, v] : dd) {
              const std::string key = py::str(k);
              if (key != "mesh" && key != "name" && key != "self")
                throw py::type_error(where + ": unknown key '" + key + "' (expected mesh, name, self)");
            }
            if (!dd.contains("mesh")) throw py::type_error(where + ": missing key 'mesh'");
            o.mesh = *as_mesh(dd["mesh"], where + ".mesh").mesh;
            if (dd.contains("name")) o.name = dd["name"].cast<std::string>();
            if (dd.contains("self")) o.self = dd["self"].cast<bool>();
          } else {
            o.mesh = *as_mesh(h, where).mesh;
          }
          if (!o.name.empty())
            for (const Object& other : objs)
              if (other.name == o.name) throw py::value_error(where + ": the name '" + o.name + "' is taken by another object");
          objs.push_back(std::move(o));
        }
        FrameResult r;
        {
          py::gil_scoped_release release;
          translate_errors([&] { d.detector.detect(objs, opt, r); });
        }
        return result_dict(r, [&](std::size_t i) { return objs[i].name; }, d.gl);
      }, py::arg("objects"), py::arg("options"), "One frame (Detector.detect(objects, **options) is the documented entry)");
}

// The exact reference: every intersecting triangle pair.
void bind_reference(py::module_& m) {
  // Packed pairs (pack_pair()) as a (k, 2) array of triangle indices.
  const auto pairs_array = [](const std::vector<std::uint64_t>& k) {
    py::array_t<std::uint32_t> out({py::ssize_t(k.size()), py::ssize_t(2)});
    auto o = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < k.size(); ++i) {
      o(i, 0) = std::uint32_t(k[i] >> 32);
      o(i, 1) = std::uint32_t(k[i] & 0xffffffffu);
    }
    return out;
  };
  m.def("exact_self_pairs", [pairs_array](const py::handle& ma) {
    const PyMesh a = as_mesh(ma, "mesh");
    std::vector<std::uint64_t> k;
    {
      py::gil_scoped_release release;
      k = exact_self_pairs(*a.mesh);
    }
    return pairs_array(k);
  }, py::arg("mesh"), "The exact self reference: every pair of one mesh's triangles that meet and share no vertex, (k, 2)");
  m.def("exact_pairs", [pairs_array](const py::handle& ma, const py::handle& mb) {
    const PyMesh a = as_mesh(ma, "a"), b = as_mesh(mb, "b");
    std::vector<std::uint64_t> k;
    {
      py::gil_scoped_release release;
      k = exact_colliding_pairs(*a.mesh, *b.mesh);  // one mesh twice: the mesh against a copy of itself
    }
    return pairs_array(k);
  }, py::arg("a"), py::arg("b"),
        "The exact reference: every colliding triangle pair of two meshes, (k, 2); one mesh given twice is tested "
        "against a copy of itself (exact_self_pairs(mesh): its self pairs)");
}

// What the library knows: its classes of geometry, its options, the GL stage's settings.
void bind_info(py::module_& m) {
  m.def("classes", []() {
    // The built-in classes of `peelcd classes` (geometry and self-collision, then containment):
    // (name, [dict(name, mesh, self)]).
    py::list out;
    const auto add = [&](const GeometryClass& g) {
      py::list objs;
      for (const Object& o : g.objects) {
        py::dict d;
        d["name"] = o.name;
        d["mesh"] = PyMesh{std::make_shared<const Mesh>(o.mesh)};
        d["self"] = o.self;
        objs.append(d);
      }
      out.append(py::make_tuple(g.name, objs));
    };
    for (const GeometryClass& g : geometry_classes(4)) add(g);
    for (const GeometryClass& g : self_classes()) add(g);
    for (const ContainmentClass& c : containment_classes()) add(c.scene);
    return out;
  }, "The classes of peelcd classes (crowded grid 4x4): a list of (name, objects)");

  m.def("options", []() {
    py::dict d;
    const DetectOptions defaults;
    for (const OptionSpec& s : option_table()) {
      const OptionValue v = s.get(defaults);
      if (const bool* b = std::get_if<bool>(&v)) d[s.key] = *b;
      else if (const double* x = std::get_if<double>(&v)) {
        if (s.kind == OptionSpec::Kind::integer) d[s.key] = static_cast<long long>(*x);
        else d[s.key] = *x;
      }
      else d[s.key] = std::get<std::string>(v);
    }
    return d;
  }, "Every option (the scene files' keys) with its default");
  m.def("gl_options", []() {
    py::dict d;
    const gl::GlOptions defaults;
    for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
      const std::string v = spec.get(defaults);
      if (*spec.choices) d[spec.key] = v;
      else d[spec.key] = v == "true";
    }
    return d;
  }, "Every GL stage setting (World, Detector and collide keywords on the osmesa and egl backends) with its default");
}

}  // namespace

PYBIND11_MODULE(_peelcd, m) {
  m.doc() = "peelcd: image-space collision detection between triangle meshes";
  m.attr("__version__") = PEELCD_VERSION_STRING;
  // NumPy's C API looked up now, while the import holds the GIL. Looked up lazily (a function-
  // local static of pybind11's), two threads' first results deadlocked: one held the static's
  // guard while importing NumPy (which lets the GIL go), the other waited on the guard holding
  // the GIL.
  py::module_::import("numpy");
  (void)py::detail::npy_api::get();
  bind_meshes(m);
  bind_world(m);
  bind_detector(m);
  bind_reference(m);
  bind_info(m);
}
