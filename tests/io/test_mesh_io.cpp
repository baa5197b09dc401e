#include "peelcd/io/error.h"
#include "peelcd/io/mesh_io.h"
#include "peelcd/io/scene.h"

#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <cstdlib>
#include <fstream>

using namespace peelcd;
namespace fs = std::filesystem;

namespace {

// Writes `text` to a fresh file named `name` in a per-test temporary folder.
std::string write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "peelcd_test_io";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

// Requires load_mesh(path) to throw an InputError whose message names the file and contains `what`.
void require_input_error(const std::string& path, const std::string& what) {
  try {
    load_mesh(path);
    FAIL("no error for " << path);
  } catch (const InputError& e) {
    const std::string msg = e.what();
    INFO(msg);
    CHECK(msg.find(path) != std::string::npos);
    CHECK(msg.find(what) != std::string::npos);
  }
}

const char* kTetraObj =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

}  // namespace

TEST_CASE("OBJ: polygons are triangulated in place, triangle order is kept", "[io]") {
  // Face 1 is a quad (-> triangles 0 and 1), face 2 a triangle (-> triangle 2).
  const std::string p = write_temp("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nf 1 2 3 4\nf 2 5 3\n");
  const Mesh m = load_mesh(p);
  REQUIRE(m.triangles.size() == 3);
  REQUIRE(m.vertices.size() == 5);
  const auto pos = [&](std::uint32_t t, int c) { return m.vertices[m.triangles[t][c]]; };
  // The last triangle is the file's second face, with its corners in order.
  CHECK(pos(2, 0) == Vec3(1, 0, 0));
  CHECK(pos(2, 1) == Vec3(5, 5, 5));
  CHECK(pos(2, 2) == Vec3(1, 1, 0));
  // The quad's two triangles only use the quad's corners.
  for (std::uint32_t t = 0; t < 2; ++t)
    for (int c = 0; c < 3; ++c) CHECK(pos(t, c).z() == 0.0);
}

TEST_CASE("OBJ, PLY, STL and OFF load the same tetrahedron with shared vertices", "[io]") {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  const std::string off = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  std::string stl = "solid t\n";
  const char* tris[4][3] = {{"0 0 0", "0 1 0", "1 0 0"}, {"0 0 0", "1 0 0", "0 0 1"},
                            {"0 0 0", "0 0 1", "0 1 0"}, {"1 0 0", "0 1 0", "0 0 1"}};
  for (auto& t : tris)
    stl += std::string("facet normal 0 0 0\nouter loop\nvertex ") + t[0] + "\nvertex " + t[1] + "\nvertex " + t[2] +
           "\nendloop\nendfacet\n";
  stl += "endsolid t\n";
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"t.obj", kTetraObj}, {"t.ply", ply},
                                   {"t.stl", stl}, {"t.off", off}}) {
    INFO(name);
    const Mesh m = load_mesh(write_temp(name, text));
    CHECK(m.triangles.size() == 4);
    CHECK(m.vertices.size() == 4);  // STL stores corners per face: welded back to 4
    // Triangle 3 is the face opposite the origin in every file.
    for (int c = 0; c < 3; ++c) CHECK(m.vertices[m.triangles[3][c]].sum() == 1.0);
  }
}

TEST_CASE("the fixture meshes load with the sizes their provenance states", "[io]") {
  const std::string dir = std::string(PEELCD_FIXTURES) + "/meshes/";
  const Mesh bunny = load_mesh(dir + "bunny_3k.obj");
  CHECK(bunny.triangles.size() == 3000);
  CHECK(bunny.vertices.size() == 1502);
  const Mesh dragon = load_mesh(dir + "dragon_3k.obj");
  CHECK(dragon.triangles.size() == 3398);
  CHECK(dragon.vertices.size() == 1699);
  // Material switches (usemtl) split assimp's meshes; the triangles still come in file order.
  const Mesh raptor = load_mesh(dir + "velociraptor.obj");
  CHECK(raptor.triangles.size() == 1248);
  CHECK(raptor.vertices.size() == 626);
}

TEST_CASE("bad mesh files give an error that names the file and the problem", "[io]") {
  const fs::path dir = fs::temp_directory_path() / "peelcd_test_io";
  fs::create_directories(dir / "a_folder.obj");
  require_input_error((dir / "missing.obj").string(), "no such file");
  require_input_error((dir / "a_folder.obj").string(), "is a directory");
  // A device (endless) and a FIFO (blocks until written): refused before any read.
  require_input_error("/dev/zero", "not a regular file");
  const fs::path fifo = dir / "pipe.obj";
  fs::remove(fifo);
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  require_input_error(fifo.string(), "not a regular file");
  CHECK_THROWS_WITH(load_scene(fifo.string()), Catch::Contains("not a regular file"));
  fs::remove(fifo);
  require_input_error(write_temp("empty.obj", ""), "the file is empty");
  require_input_error(write_temp("garbled.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n"), "element 'vertex' has no properties");
  require_input_error(write_temp("unknown.xyz123", "hello"), "cannot read");
  require_input_error(write_temp("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n"), "no triangles");
  require_input_error(write_temp("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "NaN or infinite");
  require_input_error(write_temp("inf.off", "OFF\n3 1 0\n0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n"), "NaN or infinite");
  require_input_error(write_temp("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "");
  require_input_error(write_temp("truncated.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                 "0 0 0\n1 0 0\n"),
                      "");
  require_input_error(write_temp("garbled.stl", std::string("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0") + '\0' + "\x7f\x01garbage"), "");
  require_input_error(write_temp("binary_short.stl", std::string(90, '\0')), "");
  require_input_error(write_temp("short_vertex.obj", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                      "malformed OBJ: line 1: vertex 0 has 2 coordinates, expected 3");
  require_input_error(write_temp("letters.obj", "v a b c\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "line 1: vertex 0: 'a' is not a number");
  // A coordinate that is not a number is named as such, not as a bad face index.
  require_input_error(write_temp("zz.obj", "v 0 0 0\nv 1 0 0\n# c\nv 0 1 zz\nf 1 2 3\n"), "line 4: vertex 2: 'zz' is not a number");
  // A finite value beyond float range is not "NaN or infinite".
  require_input_error(write_temp("huge.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"),
                      "vertex 1: coordinate 1e39 is outside the float range (|x| <= 3.4e38)");
  require_input_error(write_temp("huge.off", "OFF\n3 1 0\n0 0 0\n0 -1e39 0\n0 1 0\n3 0 1 2\n"),
                      "vertex 1: a coordinate is outside the float range (|x| <= 3.4e38)");
  require_input_error(write_temp("bad_face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 x\n"), "cannot read");
  require_input_error(write_temp("binary.obj", std::string("\x00\x01\x02garbage\xff\xfe", 12)), "cannot read");
  require_input_error(write_temp("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n"), "truncated");
  require_input_error(write_temp("short_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), "fewer corners");
  require_input_error(write_temp("bad_type_caps.ply", "Ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n0\n"),
                      "malformed PLY header");
  require_input_error(write_temp("bad_type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n0\n"),
                      "malformed PLY header");
  // Found by fuzzing: assimp looks for the magic after a leading line end; so does the checker.
  require_input_error(write_temp("leading_newline.ply", "\nply\nformat ascii 1.0\nel\x99ment vertex 2000000000\nend_header\n"),
                      "malformed PLY header: unknown line");
  require_input_error(write_temp("leading_nul.ply", std::string("\0x", 2) + "\nply\nformat ascii 1.0\nelement vertex 2000000000\n"
                                                                "property float x\nend_header\n1\n"),
                      "the header claims element vertex 2000000000");
  // Found by fuzzing: a count followed by other bytes read as an element without properties,
  // which assimp looped over two billion times.
  require_input_error(write_temp("element_garbage.ply", "ply\nformat ascii 1.0\nelement vertex 2000000000\xff\xff int x\n"
                                                        "end_header\n0 0 0\n"),
                      "malformed PLY header: bad element line");
  require_input_error(write_temp("element_no_properties.ply", "ply\nformat ascii 1.0\nelement vertex 2000000000\n"
                                                              "end_header\n0 0 0\n"),
                      "element 'vertex' has no properties");
  require_input_error(write_temp("bad_version.ply", "ply\nformat ascii 1$0\nelement vertex 1\nproperty float x\n"
                                                    "end_header\n0\n"),
                      "bad format line");
  require_input_error(write_temp("zero_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "");
  // Found by fuzzing: assimp's reader spins on a non-numeric value in an ASCII PLY body.
  require_input_error(write_temp("word_in_face.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                 "end_header\n0 5 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 #include0 2 3\n"),
                      "'#include0' is not a number");
}

TEST_CASE("inputs that once crashed the loader (fuzzing regressions) load or fail cleanly", "[io]") {
  // fixtures/fuzz/mesh/regression_*: first byte = format (0 OBJ, 1 PLY, 2 STL, 3 OFF), then the
  // file, as fuzz/fuzz_mesh_detect.cpp reads them.
  const char* const ext[] = {".obj", ".ply", ".stl", ".off"};
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(std::string(PEELCD_FIXTURES) + "/fuzz/mesh")) {
    if (entry.path().filename().string().rfind("regression_", 0) != 0) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE_FALSE(bytes.empty());
    const std::string path = write_temp(entry.path().filename().string() + ext[std::uint8_t(bytes[0]) % 4], bytes.substr(1));
    INFO(entry.path());
    try {
      const Mesh m = load_mesh(path);
      CHECK_FALSE(m.triangles.empty());
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find(path) != std::string::npos);
    }
    ++seen;
  }
  CHECK(seen >= 1);
}

namespace {

// Resident-set peak of this process in kB (/proc/self/status VmHWM), or -1.
long peak_rss_kb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

}  // namespace

// Loads `path` in a child process whose address space is capped (no cap under ASan, which
// reserves terabytes of shadow); the child resets its resident peak (/proc/self/clear_refs),
// loads, and reports by its exit status: 0 refused with an InputError naming the file, growing
// the peak by under 100 MB; 1 loaded; 2 refused but over the ceiling; 3 another exception
// (bad_alloc). Returns that status.
static int load_in_capped_child(const std::string& path) {
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
#if !defined(__SANITIZE_ADDRESS__)
    struct rlimit cap;
    cap.rlim_cur = cap.rlim_max = rlim_t(8) << 30;  // a regression fails here, not the machine
    ::setrlimit(RLIMIT_AS, &cap);
#endif
    std::ofstream("/proc/self/clear_refs") << "5";
    const long before = peak_rss_kb();
    int status = 1;
    try {
      load_mesh(path);
    } catch (const InputError& e) {
      status = std::string(e.what()).find(path) != std::string::npos && peak_rss_kb() - before < 100 * 1024 ? 0 : 2;
    } catch (...) {
      status = 3;
    }
    std::_Exit(status);
  }
  int status = -1;
  REQUIRE(::waitpid(child, &status, 0) == child);
  REQUIRE(WIFEXITED(status));
  return WEXITSTATUS(status);
}

TEST_CASE("a header's counts are held against the file: lying headers refused in bounded memory", "[io]") {
  // fixtures/fuzz/mesh/regression_*lying*: a header (PLY ASCII or binary, binary STL, OFF) that
  // claims up to 2e9 vertices or faces over a body of one triangle.
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(std::string(PEELCD_FIXTURES) + "/fuzz/mesh")) {
    const std::string stem = entry.path().filename().string();
    if (stem.find("lying") == std::string::npos) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const char* const ext[] = {".obj", ".ply", ".stl", ".off"};
    const std::string path = write_temp(stem + ext[std::uint8_t(bytes[0]) % 4], bytes.substr(1));
    INFO(path);
    CHECK(load_in_capped_child(path) == 0);
    ++seen;
  }
  CHECK(seen >= 5);
  // A glTF buffer whose byteLength (2e9) its file cannot hold, and an accessor of 1.7e8 vertices.
  write_temp("lying.bin", std::string(44, '\0'));
  const std::string gltf = write_temp(
      "lying.gltf",
      R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
      R"("buffers":[{"uri":"lying.bin","byteLength":2000000000}],)"
      R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":1999999000},{"buffer":0,"byteOffset":36,"byteLength":6}],)"
      R"("accessors":[{"bufferView":0,"componentType":5126,"count":166666583,"type":"VEC3","max":[1,1,0],"min":[0,0,0]},)"
      R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})");
  CHECK(load_in_capped_child(gltf) == 0);
  // And the message says what the header claimed against what the body holds.
  try {
    std::ifstream in(std::string(PEELCD_FIXTURES) + "/fuzz/mesh/regression_ply_ascii_lying_vertex_count", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    load_mesh(write_temp("lying.ply", bytes.substr(1)));
    FAIL("the lying PLY header was accepted");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("element vertex 2000000000, element face 1") && Catch::Contains("the body holds 13 numbers"));
  }
}
