#pragma once
// What the Python module's bindings share (python/module.cpp binds, python/convert.cpp converts):
// NumPy arrays and keywords into the library's meshes, poses, options and stages, results into
// dicts of NumPy arrays, the library's errors into Python's.
#include "peelcd/backends.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/world/world.h"
#include "peelcd/io/error.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace peelcd::python {

namespace py = pybind11;

// (n, 3) float64, C-contiguous: copied with one memcpy into the library's vertices. Anything
// else is refused with what it is (no silent conversion).
std::vector<Vec3> vertices_from(const py::handle& obj, const char* what);

// (m, 3) of any integer dtype, C-contiguous; indices checked against `vertex_count`.
std::vector<Tri> triangles_from(const py::handle& obj, std::size_t vertex_count, const char* what);

std::shared_ptr<const Mesh> mesh_from_arrays(const py::handle& V, const py::handle& F);

Eigen::Affine3d pose_from(const py::handle& obj);

// Keyword options, named as in scene files (theta, stage, self, volume, ...), checked as there.
DetectOptions options_from(const py::dict& kwargs);

// The GL stage's settings from keywords (gl_option_table(): peeler, resolve, batch, gpu_select, gpu_filter, coverage);
// refused on the CPU stage, which has none.
gl::GlOptions gl_options_from(const std::string& backend, const py::kwargs& kwargs);

// `costs=FILE` among a constructor's keywords, as a path (str or os.PathLike), or empty.
std::string costs_from(const py::kwargs& kwargs);

// The stage of `backend` with the GL settings `gl` and the router's models from `costs` (a file
// written by peelcd calibrate --write-costs), else $PEELCD_COSTS's, else the built-in ones.
std::shared_ptr<ImageStage> stage_for(const std::string& backend, const gl::GlOptions& gl = {},
                                      const std::string& costs = {});

// A body from Python: the id add_rigid / add_deforming returned, or the name it was given (an
// unknown one is named).
BodyId body_of(const World& world, const py::handle& body);

// One pair of a result, as NumPy arrays.
// `name_of(i)`: object or body i's name, as given ("" when none was).
py::dict pair_dict(const PairResult& p, const std::function<std::string(std::size_t)>& name_of);

py::dict result_dict(const FrameResult& r, const std::function<std::string(std::size_t)>& name_of,
                     const std::optional<gl::GlOptions>& gl = std::nullopt);

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
PyMesh as_mesh(const py::handle& obj, const std::string& where);

}  // namespace peelcd::python
