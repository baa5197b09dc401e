#pragma once
// Scene files (JSON):
//   {"objects": [{"name": "bunny", "mesh": "meshes/bunny.obj",     // relative to the scene file
//                 "transform": {"scale": 2.5, "rotate": {"axis": [0,0,1], "degrees": 0},
//                               "translate": [0.8, -0.5, 0]},
//                 "self": false},                                   // self-collision of this one
//                ...],
//    "view": {"theta": 0, "phi": 0}, "resolution": 0, "budget": 512,
//    "ids": "paper", "epsilon": 0, "peel": "full", "slope": 1}
// Everything but "objects" (and each object's "mesh") has a default (core/frame.h). Unknown
// keys, wrong types and impossible values are errors that name the file and the key.
#include "peelcd/core/frame.h"
#include "peelcd/core/mesh.h"
#include "peelcd/gl/options.h"

#include <string>
#include <vector>

namespace peelcd {

struct SceneObject {
  std::string name;
  std::string mesh_path;  // resolved against the scene file's folder
  Transform transform;
  bool self = false;  // "self": true: test the object against itself too (Object::self)
};

struct Scene {
  std::string path;
  std::vector<SceneObject> objects;
  DetectOptions options;
  gl::GlOptions gl;  // "peeler", "resolve": the GL stage's (ignored by other stages)
};

Scene parse_scene(const std::string& json_text, const std::string& path_for_messages,
                  const std::string& base_dir);
Scene load_scene(const std::string& path);  // throws InputError

// A scene of mesh files at identity transforms, named by their file names (made distinct:
// "bunny", "bunny_2"), with the default options: `peelcd detect A.obj B.obj`. Throws InputError.
Scene scene_from_meshes(const std::vector<std::string>& paths);

// Loads, validates and transforms every object's mesh into world space. Throws InputError.
std::vector<Object> load_objects(const Scene& scene);

}  // namespace peelcd
