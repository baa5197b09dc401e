// peelcd's Python module (import peelcd): meshes from NumPy arrays or files, persistent worlds of
// rigid and deforming bodies, one-shot frames, results as NumPy arrays (docs/python.md).
// Options are the scene files' keys with the same checks (peelcd/core/options.h); errors are
// Python exceptions carrying the library's messages (ValueError for bad input, RuntimeError for
// a backend that cannot start); the GIL is released while a frame runs.
#include "convert.h"

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

using namespace peelcd::python;

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
           "backend: cpu, osmesa or egl; GL backends take the GL options as keywords (peeler, resolve, batch, gpu_select, gpu_filter, coverage); "
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
           "backend: cpu, osmesa or egl; GL backends take the GL options as keywords (peeler, resolve, batch, gpu_select, gpu_filter, coverage); "
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
