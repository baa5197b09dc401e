#pragma once
// Mesh loading: OFF by peelcd's own reader, everything else (OBJ, PLY, STL, ...) through assimp. Polygons are
// triangulated in place as fans around their first corner (convex polygons, as mesh files
// hold); triangle order is the file's order (meshes of a file concatenated in
// node order). Vertices with bit-identical positions are welded, so that formats that store
// corners per face (STL, OBJ as assimp imports it) share vertices again: the paper's IDs
// (core/id_map.h) need shared vertices.
#include "peelcd/core/mesh.h"

#include <string>

namespace peelcd {

// Throws InputError naming `path` on a missing, unreadable or malformed file, a file with no
// triangles, or non-finite coordinates.
Mesh load_mesh(const std::string& path);

}  // namespace peelcd
