#include "peelcd/io/scene.h"

#include "peelcd/core/image/detector.h"
#include "peelcd/core/options.h"
#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace peelcd {
namespace {

using json = nlohmann::json;

struct Ctx {
  const std::string& path;
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError("peelcd::load_scene(): '" + path + "': " + where + ": " + what);
  }
  void only_keys(const json& j, const std::string& where, std::set<std::string> allowed) const {
    if (!j.is_object()) fail(where, "must be an object");
    for (const auto& [k, v] : j.items())
      if (!allowed.count(k)) fail(where, "unknown key \"" + k + "\"");
  }
  double number(const json& j, const std::string& where) const {
    if (!j.is_number()) fail(where, "must be a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(where, "must be finite");
    return v;
  }
  Vec3 vec3(const json& j, const std::string& where) const {
    if (!j.is_array() || j.size() != 3) fail(where, "must be an array of 3 numbers");
    return Vec3(number(j[0], where + "[0]"), number(j[1], where + "[1]"), number(j[2], where + "[2]"));
  }
  std::string string(const json& j, const std::string& where) const {
    if (!j.is_string()) fail(where, "must be a string");
    return j.get<std::string>();
  }
};

}  // namespace

Scene parse_scene(const std::string& text, const std::string& path, const std::string& base_dir) {
  const Ctx c{path};
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // a syntax error, or a number out of range (fuzzing)
    throw InputError("peelcd::load_scene(): '" + path + "': malformed JSON: " + e.what());
  }
  {
    std::set<std::string> keys = {"objects", "view"};  // and every top-level option, every GL setting
    for (const gl::GlOptionSpec& spec : gl::gl_option_table()) keys.insert(spec.key);
    for (const OptionSpec& spec : option_table())
      if (*spec.group == 0) keys.insert(spec.key);
    c.only_keys(root, "the scene", keys);
  }
  Scene scene;
  scene.path = path;
  if (!root.contains("objects")) c.fail("the scene", "missing key \"objects\"");
  const json& objs = root["objects"];
  if (!objs.is_array()) c.fail("objects", "must be an array");
  for (std::size_t i = 0; i < objs.size(); ++i) {
    const std::string where = "objects[" + std::to_string(i) + "]";
    const json& o = objs[i];
    c.only_keys(o, where, {"name", "mesh", "transform", "self"});
    SceneObject so;
    so.name = o.contains("name") ? c.string(o["name"], where + ".name") : "object" + std::to_string(i);
    if (!o.contains("mesh")) c.fail(where, "missing key \"mesh\"");
    const std::string mesh = c.string(o["mesh"], where + ".mesh");
    so.mesh_path = (std::filesystem::path(base_dir) / mesh).lexically_normal().string();
    if (o.contains("transform")) {
      const json& t = o["transform"];
      const std::string tw = where + ".transform";
      c.only_keys(t, tw, {"scale", "rotate", "translate"});
      if (t.contains("scale")) {
        so.transform.scale = c.number(t["scale"], tw + ".scale");
        if (!(so.transform.scale > 0)) c.fail(tw + ".scale", "must be positive");
        // The image stage works in float: a scale below float's smallest normal number shrinks
        // any mesh to a point there.
        if (so.transform.scale < 1.1754943508222875e-38)
          c.fail(tw + ".scale", "must be at least 1.2e-38 (float's smallest normal number: a smaller one shrinks the mesh to a point)");
      }
      if (t.contains("rotate")) {
        const json& r = t["rotate"];
        c.only_keys(r, tw + ".rotate", {"axis", "degrees"});
        if (r.contains("axis")) so.transform.axis = c.vec3(r["axis"], tw + ".rotate.axis");
        if (r.contains("degrees")) so.transform.degrees = c.number(r["degrees"], tw + ".rotate.degrees");
        if (so.transform.degrees != 0 && !(so.transform.axis.cwiseAbs().maxCoeff() > 0))
          c.fail(tw + ".rotate.axis", "must not be zero");
      }
      if (t.contains("translate")) so.transform.translate = c.vec3(t["translate"], tw + ".translate");
    }
    if (o.contains("self")) {
      if (!o["self"].is_boolean()) c.fail(where + ".self", "must be true or false");
      so.self = o["self"].get<bool>();
    }
    scene.objects.push_back(std::move(so));
  }
  if (scene.objects.empty()) c.fail("objects", "must name at least one object");
  // Names identify objects in results and dumps: each once.
  for (std::size_t i = 0; i < scene.objects.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (scene.objects[i].name == scene.objects[j].name)
        c.fail("objects[" + std::to_string(i) + "].name",
               "duplicate name \"" + scene.objects[i].name + "\" (also objects[" + std::to_string(j) + "])");
  DetectOptions& opt = scene.options;
  // The options, from the one table (peelcd/core/options.h): a key at the top level, or in
  // "view" (theta, phi, roll); each value checked with a message that names its key.
  const auto read = [&](const OptionSpec& spec, const json& j, const std::string& where) {
    OptionValue value;
    switch (spec.kind) {
      case OptionSpec::Kind::boolean:
        if (!j.is_boolean()) c.fail(where, "must be true or false");
        value = j.get<bool>();
        break;
      case OptionSpec::Kind::choice:
        value = c.string(j, where);
        break;
      default:
        if (!j.is_number())
          c.fail(where, std::string("must be a number, got ") + (j.is_string() ? "the string " + j.dump() : std::string("a ") + j.type_name()));
        value = j.get<double>();
    }
    if (const std::string problem = check_option(spec, value); !problem.empty()) c.fail(where, problem);
    spec.set(opt, value);
  };
  if (root.contains("view")) {
    const json& v = root["view"];
    std::set<std::string> keys;
    for (const OptionSpec& spec : option_table())
      if (std::string(spec.group) == "view") keys.insert(spec.key);
    c.only_keys(v, "view", keys);
    // A view that names theta or phi means the paper's frame turned there: roll 0 unless given.
    for (const OptionSpec& spec : option_table())
      if (sets_view_direction(spec) && v.contains(spec.key)) opt.roll = 0.0;
  }
  for (const OptionSpec& spec : option_table()) {
    const std::string group = spec.group;
    const json* holder = group.empty() ? &root : root.contains(group) ? &root[group] : nullptr;
    if (holder && holder->contains(spec.key))
      read(spec, (*holder)[spec.key], group.empty() ? std::string(spec.key) : group + "." + spec.key);
  }
  // The GL stage's settings (gl_option_table()): a choice's word, or a boolean.
  for (const gl::GlOptionSpec& spec : gl::gl_option_table()) {
    if (!root.contains(spec.key)) continue;
    const json& v = root[spec.key];
    std::string words;
    if (*spec.choices) words = c.string(v, spec.key);
    else if (v.is_boolean()) words = v.get<bool>() ? "true" : "false";
    else c.fail(spec.key, "must be true or false");
    const std::string problem = gl::set_gl_option(scene.gl, spec.key, words);
    if (!problem.empty()) c.fail(spec.key, problem.substr(problem.find(": ") + 2));
  }
  return scene;
}

Scene load_scene(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError("peelcd::load_scene(): '" + path + "': no such file");
  if (fs::is_directory(path, ec)) throw InputError("peelcd::load_scene(): '" + path + "': is a directory");
  if (!fs::is_regular_file(path, ec))
    throw InputError("peelcd::load_scene(): '" + path + "': not a regular file (a device, a FIFO or a socket)");
  std::ifstream in(path);
  if (!in) throw InputError("peelcd::load_scene(): '" + path + "': cannot open it");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), path, fs::path(path).parent_path().string());
}

Scene scene_from_meshes(const std::vector<std::string>& paths) {
  Scene scene;
  scene.path = "(meshes on the command line)";
  for (const std::string& path : paths) {
    SceneObject so;
    so.mesh_path = path;
    so.name = std::filesystem::path(path).stem().string();
    if (so.name.empty()) so.name = "object";
    // Names from the file names, made distinct: bunny, bunny_2, ...
    const std::string base = so.name;
    for (int k = 2;; ++k) {
      bool taken = false;
      for (const SceneObject& other : scene.objects) taken = taken || other.name == so.name;
      if (!taken) break;
      so.name = base + "_" + std::to_string(k);
    }
    scene.objects.push_back(std::move(so));
  }
  if (scene.objects.empty()) throw InputError("peelcd: no meshes given");
  return scene;
}

std::vector<Object> load_objects(const Scene& scene) {
  std::vector<Object> out;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& so = scene.objects[i];
    const std::string where = "'" + scene.path + "': objects[" + std::to_string(i) + "] (\"" + so.name + "\")";
    // A glTF / GLB file with several mesh nodes becomes one object per node: named by the node
    // ("object/node" when the scene has other objects too).
    std::vector<NamedMesh> parts;
    try {  // a mesh's problem names the scene and the object that referenced it
      if (is_node_scene(so.mesh_path)) parts = load_mesh_nodes(so.mesh_path);
      else parts.push_back({so.name, load_mesh(so.mesh_path)});
    } catch (const InputError& e) {
      throw InputError(std::string(e.what()) + " (referenced by " + where + ")");
    }
    for (NamedMesh& part : parts) {
      Object o;
      o.name = parts.size() == 1 ? so.name : scene.objects.size() == 1 ? part.name : so.name + "/" + part.name;
      const Mesh raw = std::move(part.mesh);
      o.mesh = transformed(raw, so.transform);
      o.self = so.self;
      try {
        validate_mesh(raw, "'" + so.mesh_path + "'");
      } catch (const std::invalid_argument& e) {
        throw InputError(std::string("peelcd::load_objects(): ") + e.what());
      }
      // The image stage uploads float coordinates: beyond float's range a vertex becomes infinite
      // (kFloatMax, the limit Detector::detect() checks too).
      for (const Vec3& v : o.mesh.vertices)
        if (!v.allFinite() || v.cwiseAbs().maxCoeff() > kFloatMax) {
          char buf[160];
          std::snprintf(buf, sizeof buf, "(%g, %g, %g)", v.x(), v.y(), v.z());
          throw InputError("peelcd::load_objects(): " + where + ": the transform gives the vertex " + buf +
                           ", outside the float range (|x| <= 3.4e38) the image stage works in: scale or "
                           "translation too large");
        }
      try {
        validate_mesh(o.mesh, where);
      } catch (const std::invalid_argument& e) {
        throw InputError(std::string("peelcd::load_objects(): ") + e.what());
      }
      // A mesh with extent that the transform shrinks to a point in float (the image stage's
      // precision) is refused: it would be reported as inside whatever holds that point.
      const auto float_extent = [](const Mesh& m) {
        Eigen::Vector3f lo = Eigen::Vector3f::Constant(INFINITY), hi = -lo;
        for (const Vec3& v : m.vertices) {
          lo = lo.cwiseMin(v.cast<float>());
          hi = hi.cwiseMax(v.cast<float>());
        }
        return (hi - lo).maxCoeff();
      };
      if (float_extent(raw) > 0.0f && !(float_extent(o.mesh) > 0.0f))
        throw InputError("peelcd::load_objects(): " + where + ": the transform shrinks the mesh to a point (in float, the "
                         "image stage's precision)");
      out.push_back(std::move(o));
    }
  }
  return out;
}

}  // namespace peelcd
