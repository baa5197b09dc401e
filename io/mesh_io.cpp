#include "io/mesh_io.h"

#include "io/error.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <filesystem>
#include <functional>
#include <unordered_map>

namespace peelcd {
namespace {

struct PositionHash {
  std::size_t operator()(const Vec3& p) const {
    std::size_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; ++k) h = (h ^ std::hash<double>()(p[k])) * 1099511628211ull;
    return h;
  }
};

void append_node(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, Mesh& out,
                 std::unordered_map<Vec3, std::uint32_t, PositionHash>& weld, const std::string& path) {
  const aiMatrix4x4 xf = parent * node->mTransformation;
  for (unsigned i = 0; i < node->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[node->mMeshes[i]];
    std::vector<std::uint32_t> remap(m->mNumVertices);
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const aiVector3D p = xf * m->mVertices[v];
      const Vec3 q(p.x, p.y, p.z);
      if (!q.allFinite())
        throw InputError("peelcd::load_mesh(): '" + path + "': vertex " + std::to_string(v) +
                         " has a NaN or infinite coordinate");
      auto [it, inserted] = weld.emplace(q, std::uint32_t(out.vertices.size()));
      if (inserted) out.vertices.push_back(q);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not surfaces
      Tri t;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= m->mNumVertices)
          throw InputError("peelcd::load_mesh(): '" + path + "': face " + std::to_string(f) +
                           " uses a vertex index out of range");
        t[k] = remap[face.mIndices[k]];
      }
      out.triangles.push_back(t);
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) append_node(scene, node->mChildren[c], xf, out, weld, path);
}

}  // namespace

Mesh load_mesh(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError("peelcd::load_mesh(): '" + path + "': no such file");
  if (fs::is_directory(path, ec)) throw InputError("peelcd::load_mesh(): '" + path + "': is a directory, not a mesh file");
  if (fs::file_size(path, ec) == 0) throw InputError("peelcd::load_mesh(): '" + path + "': the file is empty");

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError("peelcd::load_mesh(): '" + path + "': cannot read it as a mesh: " +
                     importer.GetErrorString());
  Mesh mesh;
  std::unordered_map<Vec3, std::uint32_t, PositionHash> weld;
  append_node(scene, scene->mRootNode, aiMatrix4x4(), mesh, weld, path);
  if (mesh.triangles.empty()) throw InputError("peelcd::load_mesh(): '" + path + "': the file has no triangles");
  return mesh;
}

}  // namespace peelcd
