#pragma once
// Mesh loading: OFF by peelcd's own reader, everything else (OBJ, PLY, STL, ...) through assimp. Polygons are
// triangulated in place as fans around their first corner (convex polygons, as mesh files
// hold); triangle order is the file's order (meshes of a file concatenated in
// node order). Vertices with bit-identical positions are welded, so that formats that store
// corners per face (STL, OBJ as assimp imports it) share vertices again: the paper's IDs
// (core/image/id_map.h) need shared vertices.
#include "peelcd/core/mesh.h"

#include <string>

namespace peelcd {

// Throws InputError naming `path` on a missing, unreadable or malformed file, a file with no
// triangles, or non-finite coordinates.
Mesh load_mesh(const std::string& path);

// A glTF / GLB file (.gltf, .glb) is a scene of nodes: one mesh per node that holds meshes, in
// the node's world transform (the node's and its parents'), named by the node (made distinct).
// Any other file gives one mesh named by the file's stem. Throws InputError.
struct NamedMesh {
  std::string name;
  Mesh mesh;
};
bool is_node_scene(const std::string& path);
std::vector<NamedMesh> load_mesh_nodes(const std::string& path);

}  // namespace peelcd
