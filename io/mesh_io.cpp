#include "peelcd/io/mesh_io.h"

#include "peelcd/core/image/detector.h"  // kFloatMax
#include "peelcd/io/error.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <functional>
#include <set>
#include <sstream>
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
                 std::unordered_map<Vec3, std::uint32_t, PositionHash>& weld, const std::string& path,
                 bool recurse = true) {
  const aiMatrix4x4 xf = parent * node->mTransformation;
  // A singular node transform (a scale of 0) flattens or collapses its meshes: refused, as a
  // scene file's scale 0 is.
  if (node->mNumMeshes > 0 && !(std::abs(xf.Determinant()) > 0.0f))
    throw InputError("peelcd::load_mesh(): '" + path + "': node '" + std::string(node->mName.C_Str()) +
                     "': its transform is singular (a scale of 0): it would collapse its meshes");
  for (unsigned i = 0; i < node->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[node->mMeshes[i]];
    std::vector<std::uint32_t> remap(m->mNumVertices);
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const aiVector3D p = xf * m->mVertices[v];
      const Vec3 q(p.x, p.y, p.z);
      if (!q.allFinite())
        throw InputError("peelcd::load_mesh(): '" + path + "': vertex " + std::to_string(v) +
                         " has a NaN or infinite coordinate (files other than OFF are read at float precision: "
                         "a value beyond 3.4e38 in the file reads as infinite)");
      auto [it, inserted] = weld.emplace(q, std::uint32_t(out.vertices.size()));
      if (inserted) out.vertices.push_back(q);
      remap[v] = it->second;
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices < 3 || !face.mIndices) continue;  // points and lines are not surfaces
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= m->mNumVertices)
          throw InputError("peelcd::load_mesh(): '" + path + "': face " + std::to_string(f) +
                           " uses a vertex index out of range");
      // Polygons become a fan around their first corner, in place: (0, k, k + 1).
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k)
        out.triangles.push_back({remap[face.mIndices[0]], remap[face.mIndices[k]], remap[face.mIndices[k + 1]]});
    }
  }
  if (recurse)
    for (unsigned c = 0; c < node->mNumChildren; ++c) append_node(scene, node->mChildren[c], xf, out, weld, path);
}

// Every node that holds meshes, with its world transform, in depth-first order.
void mesh_nodes(const aiNode* node, const aiMatrix4x4& parent,
                std::vector<std::pair<const aiNode*, aiMatrix4x4>>& out) {
  const aiMatrix4x4 xf = parent * node->mTransformation;
  if (node->mNumMeshes > 0) out.push_back({node, parent});
  for (unsigned c = 0; c < node->mNumChildren; ++c) mesh_nodes(node->mChildren[c], xf, out);
}

// Bytes of a PLY scalar type (the header checker has checked the name).
std::size_t ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "double" || t == "float64") return 8;
  return 4;  // int, uint, float, int32, uint32, float32
}

// Whether `s` is a whole number in the C locale's syntax (a PLY version: "1.0").
bool is_number(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}

// Checks the header of an ASCII or binary PLY file line by line before assimp sees it: assimp
// 5.2's PLY reader loops forever on some malformed headers (an unknown property type, found by
// fuzzing), and on an ASCII body with a value that is not a number (`3 #include0 2 3` as a face
// line, found by fuzzing: assimp spins in its reader), and on a control character in a header
// line. And a header's element counts are held against the body before anything is allocated
// from them: assimp reserves what a count claims (a 198-byte ASCII file claiming 2e9 vertices
// grew to 23 GB), so a body too short for its counts (a binary body: the bytes of each element
// with empty lists; an ASCII body: one number per scalar property and per list) is refused.
// Returns an empty string if the file is well-formed so far, else the problem.
std::string ply_header_problem(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line)) return "";
  // assimp's line reader skips a first line that begins with a line end ('\n', '\r', '\0' or
  // '\f') through its '\n' and looks for the magic on the next one (a file "\nply\n..." is read
  // as PLY: found by fuzzing, with a header assimp then spun on); this checker reads it the same.
  if (line.empty() || line[0] == '\r' || line[0] == '\0' || line[0] == '\f')
    if (!std::getline(in, line)) return "";
  for (char& c : line) c = char(std::tolower(static_cast<unsigned char>(c)));  // assimp accepts "Ply"
  if (line.rfind("ply", 0) != 0) return "";  // not a PLY file: assimp decides
  static const std::set<std::string> types = {"char",  "uchar", "short",  "ushort",  "int",     "uint",
                                              "float", "double", "int8",  "uint8",   "int16",   "uint16",
                                              "int32", "uint32", "float32", "float64"};
  struct Element {
    std::string name;
    long double count = 0;           // as claimed (long double: a product with it cannot overflow)
    std::size_t min_bytes = 0;       // binary: scalar sizes + list count sizes (empty lists)
    std::size_t min_numbers = 0;     // ASCII: one per scalar property and per list
  };
  std::vector<Element> elements;
  bool ascii = false;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // assimp splits header lines at spaces and tabs only: a line it would not end where this
    // reader does (a vertical tab after end_header, found by fuzzing: assimp spins) is refused.
    for (const char c : line)
      if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
        return "malformed PLY header: control character " + std::to_string(int(static_cast<unsigned char>(c))) +
               " in line " + std::to_string(n + 2);
    std::istringstream words(line);
    std::string w;
    words >> w;
    if (w == "end_header") {
      if (!elements.empty() && elements.back().count > 0 && elements.back().min_numbers == 0)
        return "malformed PLY header: element '" + elements.back().name + "' has no properties";
      long double need = 0;
      for (const Element& e : elements) need += e.count * (ascii ? e.min_numbers : e.min_bytes);
      const auto claimed = [&] {
        std::string s;
        for (const Element& e : elements) s += (s.empty() ? "" : ", ") + ("element " + e.name + " " + std::to_string((long long)e.count));
        return s;
      };
      if (!ascii) {
        const std::streamoff body_start = in.tellg();
        in.seekg(0, std::ios::end);
        const long double body = body_start < 0 ? 0.0L : (long double)(in.tellg() - body_start);
        if (need > body)
          return "malformed PLY: the header claims " + claimed() + ", at least " + std::to_string((unsigned long long)std::min(need, 1.8e19L)) +
                 " bytes, but the body holds " + std::to_string((unsigned long long)body) + " bytes";
        return "";
      }
      // An ASCII body holds numbers only (comments belong to the header).
      long double numbers = 0;
      for (std::string value; in >> value; numbers += 1) {
        char* end = nullptr;
        std::strtod(value.c_str(), &end);
        if (end != value.c_str() + value.size())
          return "malformed PLY body: '" + value.substr(0, 40) + "' is not a number";
      }
      if (need > numbers)
        return "malformed PLY: the header claims " + claimed() + ", at least " + std::to_string((unsigned long long)std::min(need, 1.8e19L)) +
               " numbers, but the body holds " + std::to_string((unsigned long long)numbers) + " numbers";
      return "";
    }
    if (w == "comment" || w == "obj_info" || w.empty()) continue;
    // A line with words after the ones it takes is refused: `element vertex 2000000000<bytes>
    // int ...` (found by fuzzing) read as a count and nothing else gave an element without
    // properties that assimp looped over two billion times.
    const auto ends = [&words] {
      std::string extra;
      return !(words >> extra);
    };
    if (w == "format") {
      std::string kind, version;
      if (!(words >> kind >> version) || !ends() ||
          (kind != "ascii" && kind != "binary_little_endian" && kind != "binary_big_endian") ||
          !is_number(version))
        return "malformed PLY header: bad format line '" + line + "'";
      ascii = kind == "ascii";
    } else if (w == "element") {
      std::string name;
      long long count = -1;
      if (!(words >> name >> count) || count < 0 || !ends())
        return "malformed PLY header: bad element line '" + line + "'";
      if (!elements.empty() && elements.back().count > 0 && elements.back().min_numbers == 0)
        return "malformed PLY header: element '" + elements.back().name + "' has no properties";
      elements.push_back({name, (long double)count, 0, 0});
    } else if (w == "property") {
      std::string type, name;
      if (!(words >> type)) return "malformed PLY header: empty property line";
      if (type == "list") {
        std::string count_type, item_type;
        if (!(words >> count_type >> item_type >> name) || !ends() || !types.count(count_type) || !types.count(item_type))
          return "malformed PLY header: bad property list line '" + line + "'";
        type = count_type;  // an empty list: its count alone
      } else if (!types.count(type) || !(words >> name) || !ends()) {
        return "malformed PLY header: bad property line '" + line + "'";
      }
      if (elements.empty()) return "malformed PLY header: a property before any element: '" + line + "'";
      elements.back().min_bytes += ply_type_size(type);
      elements.back().min_numbers += 1;
    } else {
      return "malformed PLY header: unknown line '" + line + "'";
    }
  }
  return "malformed PLY header: no end_header";
}

// Checks the vertex lines of an OBJ file before assimp reads it: assimp parses a coordinate that
// is not a number as 0 or skips it (`v 0 1 zz` then surfaced as "vertex index out of range"),
// and reads at float precision, where a finite value beyond 3.4e38 becomes infinite. Returns an
// empty string if every `v` line holds 3 or 4 numbers within float's range, else the problem
// (with the line number).
std::string obj_vertex_problem(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  std::size_t vertex = 0;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string w;
    if (!(words >> w) || w != "v") continue;
    int count = 0;
    const std::string where = "line " + std::to_string(number) + ": vertex " + std::to_string(vertex);
    while (words >> w) {
      if (w[0] == '#') break;
      char* end = nullptr;
      const double x = std::strtod(w.c_str(), &end);
      if (end != w.c_str() + w.size()) return where + ": '" + w.substr(0, 40) + "' is not a number";
      if (count < 3 && std::isfinite(x) && std::abs(x) > kFloatMax)
        return where + ": coordinate " + w.substr(0, 40) +
               " is outside the float range (|x| <= 3.4e38) mesh files are read in";
      ++count;
    }
    if (count < 3) return where + " has " + std::to_string(count) + " coordinates, expected 3";
    ++vertex;
  }
  return "";
}

// OFF is read here, not by assimp: assimp 5.2's OFF reader crashes (SEGV, or an assertion in
// its triangulation) on malformed files, found by fuzzing. Format: optional "OFF" keyword, then
// "V F E", V lines "x y z", F lines "n i1 .. in" (extra values, e.g. colours, ignored); '#'
// starts a comment. Polygons become fans in place, as for the other formats.
Mesh read_off(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream lines(text);
  std::vector<std::string> rows;
  for (std::string line; std::getline(lines, line);) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    if (line.find_first_not_of(" \t\r") != std::string::npos) rows.push_back(line);
  }
  const auto fail = [&](const std::string& what) -> InputError {
    return InputError("peelcd::load_mesh(): '" + path + "': malformed OFF: " + what);
  };
  std::size_t row = 0;
  if (row < rows.size() && rows[row].find("OFF") != std::string::npos) ++row;
  long long nv = -1, nf = -1;
  if (row >= rows.size() || !(std::istringstream(rows[row++]) >> nv >> nf) || nv < 0 || nf < 0)
    throw fail("missing or bad vertex and face counts");
  if (rows.size() - row < std::size_t(nv) + std::size_t(nf))
    throw fail("the file is truncated (" + std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces announced, " + std::to_string(rows.size() - row) + " lines found)");
  Mesh mesh;
  std::vector<std::uint32_t> remap(static_cast<std::size_t>(nv));
  std::unordered_map<Vec3, std::uint32_t, PositionHash> weld;
  for (long long v = 0; v < nv; ++v) {
    std::istringstream r(rows[row++]);
    std::string x, y, z;
    if (!(r >> x >> y >> z)) throw fail("vertex " + std::to_string(v) + " has fewer than 3 coordinates");
    Vec3 p;
    try {
      p = Vec3(std::stod(x), std::stod(y), std::stod(z));
    } catch (const std::exception&) {
      throw fail("vertex " + std::to_string(v) + " has a coordinate that is not a number");
    }
    if (!p.allFinite())
      throw InputError("peelcd::load_mesh(): '" + path + "': vertex " + std::to_string(v) +
                       " has a NaN or infinite coordinate");
    if (p.cwiseAbs().maxCoeff() > kFloatMax)
      throw fail("vertex " + std::to_string(v) + ": a coordinate is outside the float range (|x| <= 3.4e38) the image stage works in");
    auto [it, inserted] = weld.emplace(p, std::uint32_t(mesh.vertices.size()));
    if (inserted) mesh.vertices.push_back(p);
    remap[std::size_t(v)] = it->second;
  }
  for (long long f = 0; f < nf; ++f) {
    std::istringstream r(rows[row++]);
    long long n = 0;
    if (!(r >> n) || n < 0) throw fail("face " + std::to_string(f) + " has no corner count");
    std::vector<std::uint32_t> corners;
    for (long long k = 0; k < n; ++k) {
      long long i = -1;
      if (!(r >> i)) throw fail("face " + std::to_string(f) + " has fewer corners than it announces");
      if (i < 0 || i >= nv)
        throw InputError("peelcd::load_mesh(): '" + path + "': face " + std::to_string(f) +
                         " uses a vertex index out of range");
      corners.push_back(remap[std::size_t(i)]);
    }
    for (std::size_t k = 1; k + 1 < corners.size(); ++k) mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
  }
  if (mesh.triangles.empty()) throw InputError("peelcd::load_mesh(): '" + path + "': the file has no triangles");
  return mesh;
}

}  // namespace

namespace {

// The checks every mesh file gets, then assimp's import (no post-processing: its triangulation
// asserts (aborts) on some malformed files, which fuzzing found (docs/robustness.md); polygons
// are split in append_node instead). Null for OFF files, which peelcd reads itself.
const aiScene* import_checked(const std::string& path, Assimp::Importer& importer) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError("peelcd::load_mesh(): '" + path + "': no such file");
  if (fs::is_directory(path, ec)) throw InputError("peelcd::load_mesh(): '" + path + "': is a directory, not a mesh file");
  // A device (/dev/zero: endless), a FIFO (blocks until written) or a socket is no mesh file.
  if (!fs::is_regular_file(path, ec))
    throw InputError("peelcd::load_mesh(): '" + path + "': not a regular file (a device, a FIFO or a socket)");
  if (fs::file_size(path, ec) == 0) throw InputError("peelcd::load_mesh(): '" + path + "': the file is empty");
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".obj") {  // a text format: binary data is said as such (assimp would find "no triangles")
    std::ifstream in(path, std::ios::binary);
    char buf[65536];
    in.read(buf, sizeof buf);
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      const unsigned char ch = static_cast<unsigned char>(buf[i]);
      if (ch == 0 || (ch < 0x20 && ch != '\t' && ch != '\n' && ch != '\r' && ch != '\f' && ch != '\v'))
        throw InputError("peelcd::load_mesh(): '" + path + "': cannot read: binary data at byte " + std::to_string(i) +
                         " (an OBJ file is text)");
    }
  }
  if (ext == ".off") return nullptr;
  if (const std::string problem = ply_header_problem(path); !problem.empty())
    throw InputError("peelcd::load_mesh(): '" + path + "': " + problem);
  if (ext == ".obj")
    if (const std::string problem = obj_vertex_problem(path); !problem.empty())
      throw InputError("peelcd::load_mesh(): '" + path + "': malformed OBJ: " + problem);
  const aiScene* scene = importer.ReadFile(path, 0);
  if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError("peelcd::load_mesh(): '" + path + "': cannot read it as a mesh: " +
                     importer.GetErrorString());
  return scene;
}

}  // namespace

Mesh load_mesh(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = import_checked(path, importer);
  if (!scene) return read_off(path);
  Mesh mesh;
  std::unordered_map<Vec3, std::uint32_t, PositionHash> weld;
  append_node(scene, scene->mRootNode, aiMatrix4x4(), mesh, weld, path);
  if (mesh.triangles.empty()) throw InputError("peelcd::load_mesh(): '" + path + "': the file has no triangles");
  return mesh;
}

bool is_node_scene(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".gltf" || ext == ".glb";
}

std::vector<NamedMesh> load_mesh_nodes(const std::string& path) {
  if (!is_node_scene(path)) return {{std::filesystem::path(path).stem().string(), load_mesh(path)}};
  Assimp::Importer importer;
  const aiScene* scene = import_checked(path, importer);  // never null: not an OFF file
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> nodes;
  mesh_nodes(scene->mRootNode, aiMatrix4x4(), nodes);
  std::vector<NamedMesh> out;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    NamedMesh n;
    n.name = nodes[k].first->mName.length ? nodes[k].first->mName.C_Str() : "node" + std::to_string(k);
    std::unordered_map<Vec3, std::uint32_t, PositionHash> weld;
    append_node(scene, nodes[k].first, nodes[k].second, n.mesh, weld, path, false);
    if (n.mesh.triangles.empty()) continue;  // a node of points or lines only
    // Node names need not be unique in glTF: made distinct (name, name_2, ...).
    const std::string base = n.name;
    for (int i = 2;; ++i) {
      bool taken = false;
      for (const NamedMesh& o : out) taken = taken || o.name == n.name;
      if (!taken) break;
      n.name = base + "_" + std::to_string(i);
    }
    out.push_back(std::move(n));
  }
  if (out.empty()) throw InputError("peelcd::load_mesh(): '" + path + "': the file has no triangles");
  return out;
}

}  // namespace peelcd
