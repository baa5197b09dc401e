// A dump writer independent of peelcd's dump code (oracle/dump.cpp, oracle/images.cpp): it
// follows docs/dump-format.md as another implementation would, with its own uncompressed
// scanline EXR encoder (no OpenEXR library) and its own meta.json. The layers come from peelcd's
// CPU image stage; `peelcd golden compare-dumps` must find this dump equal to `peelcd dump
// --backend cpu` of the same scene (tests/oracle/test_dumps.cmake).
//
//   independent_dump_writer SCENE OUT_DIR
#include "peelcd/core/image/cpu_stage.h"
#include "peelcd/core/image/detector.h"
#include "peelcd/core/exact/reference.h"
#include "peelcd/io/scene.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace peelcd;

namespace {

// ---- a minimal OpenEXR 2.0 writer: single part, scanline, NO_COMPRESSION ----
struct Bytes {
  std::vector<char> data;
  void raw(const void* p, std::size_t n) { data.insert(data.end(), (const char*)p, (const char*)p + n); }
  void i32(std::int32_t v) { raw(&v, 4); }  // EXR is little-endian, as is this machine (x86-64)
  void u64(std::uint64_t v) { raw(&v, 8); }
  void f32(float v) { raw(&v, 4); }
  void u8(std::uint8_t v) { raw(&v, 1); }
  void str(const std::string& s) { raw(s.c_str(), s.size() + 1); }
  void attribute(const std::string& name, const std::string& type, const Bytes& value) {
    str(name);
    str(type);
    i32(std::int32_t(value.data.size()));
    raw(value.data.data(), value.data.size());
  }
};

// Channels in the file's (alphabetical) order: Z, dzdx, dzdy, id, object.
// `planes` holds one n*n plane per channel, rows top to bottom, as 32-bit words.
void write_exr(const fs::path& path, int n, const std::vector<std::vector<std::uint32_t>>& planes) {
  static const char* const names[5] = {"Z", "dzdx", "dzdy", "id", "object"};
  static const std::int32_t types[5] = {2, 2, 2, 0, 0};  // 2 = FLOAT, 0 = UINT
  Bytes f;
  f.i32(20000630);  // magic
  f.i32(2);         // version 2, no flags: single-part scanline
  Bytes ch;
  for (int c = 0; c < 5; ++c) {
    ch.str(names[c]);
    ch.i32(types[c]);
    ch.u8(0);  // pLinear
    ch.u8(0), ch.u8(0), ch.u8(0);
    ch.i32(1), ch.i32(1);  // x and y sampling
  }
  ch.u8(0);
  f.attribute("channels", "chlist", ch);
  Bytes comp;
  comp.u8(0);  // NO_COMPRESSION
  f.attribute("compression", "compression", comp);
  Bytes box;
  box.i32(0), box.i32(0), box.i32(n - 1), box.i32(n - 1);
  f.attribute("dataWindow", "box2i", box);
  f.attribute("displayWindow", "box2i", box);
  Bytes order;
  order.u8(0);  // INCREASING_Y
  f.attribute("lineOrder", "lineOrder", order);
  Bytes one;
  one.f32(1.0f);
  f.attribute("pixelAspectRatio", "float", one);
  Bytes centre;
  centre.f32(0.0f), centre.f32(0.0f);
  f.attribute("screenWindowCenter", "v2f", centre);
  f.attribute("screenWindowWidth", "float", one);
  f.u8(0);  // end of header
  const std::size_t line_bytes = std::size_t(n) * 4 * 5;
  const std::size_t table_at = f.data.size(), blocks_at = table_at + 8 * std::size_t(n);
  for (int y = 0; y < n; ++y) f.u64(blocks_at + std::size_t(y) * (8 + line_bytes));
  for (int y = 0; y < n; ++y) {
    f.i32(y);
    f.i32(std::int32_t(line_bytes));
    for (int c = 0; c < 5; ++c) f.raw(&planes[c][std::size_t(y) * n], std::size_t(n) * 4);
  }
  std::ofstream out(path, std::ios::binary);
  out.write(f.data.data(), std::streamsize(f.data.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// A captured layer (GL row order, bottom row first; 4 words per texel: depth, object << 31 |
// ID + 1, two more words) as the five planes of docs/dump-format.md, rows top to bottom.
std::vector<std::vector<std::uint32_t>> planes_of(const std::vector<std::uint32_t>& layer, int n) {
  std::vector<std::vector<std::uint32_t>> p(5, std::vector<std::uint32_t>(std::size_t(n) * n));
  for (int row = 0; row < n; ++row)
    for (int x = 0; x < n; ++x) {
      const std::size_t src = std::size_t(row) * n + x, dst = std::size_t(n - 1 - row) * n + x;
      const std::uint32_t word = layer[4 * src + 1];
      p[0][dst] = layer[4 * src];          // Z
      p[1][dst] = layer[4 * src + 2];      // dzdx (conservative: upper depth)
      p[2][dst] = layer[4 * src + 3];      // dzdy
      p[3][dst] = word & 0x7fffffffu;      // id = ID + 1, 0 = empty
      p[4][dst] = word ? word >> 31 : 0u;  // object
    }
  return p;
}

void text(const fs::path& path, const std::string& s) {
  std::ofstream out(path);
  out << s;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

std::string safe(const std::string& name) {
  std::string s;
  for (char c : name) s += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: independent_dump_writer SCENE OUT_DIR\n");
    return 2;
  }
  try {
    const Scene scene = load_scene(argv[1]);
    const std::vector<Object> objects = load_objects(scene);
    DetectOptions opt = scene.options;
    opt.stage = Stage::image;  // a dump holds the image stage's layers
    auto stage = std::make_shared<CpuImageStage>();
    Detector detector(stage);
    std::vector<CapturedView> captured;
    detector.capture_layers(&captured);
    const FrameResult frame = detector.detect(objects, opt);

    const fs::path root = argv[2];
    fs::create_directories(root);
    nlohmann::json pairs = nlohmann::json::array();
    for (std::size_t i = 0; i < frame.pairs.size(); ++i) {
      const PairResult& r = frame.pairs[i];
      const std::string& a = objects[r.object_a].name;
      const std::string& b = objects[r.object_b].name;
      const std::string dir = "pair" + std::to_string(i) + "_" + safe(a) + "_" + safe(b);
      fs::create_directories(root / dir);
      std::string pcs, colliding, reference;
      for (const IdPair& p : r.pcs) pcs += std::to_string(p.a) + " " + std::to_string(p.b) + "\n";
      for (const Contact& c : r.colliding)
        colliding += std::to_string(c.tri_a) + " " + std::to_string(c.tri_b) + " " + to_string(c.kind) + "\n";
      const auto exact = exact_colliding_pairs(objects[r.object_a].mesh, objects[r.object_b].mesh);
      for (std::uint64_t k : exact) reference += std::to_string(k >> 32) + " " + std::to_string(k & 0xffffffffu) + "\n";
      text(root / dir / "pcs.txt", pcs);
      text(root / dir / "colliding.txt", colliding);
      text(root / dir / "reference.txt", reference);
      nlohmann::json views = nlohmann::json::array();
      for (const CapturedView& v : captured) {
        if (v.pair != i) continue;
        const std::string vdir = dir + "/view" + std::to_string(v.view);
        fs::create_directories(root / vdir);
        std::string vpcs;
        for (const IdPair& p : v.pcs) vpcs += std::to_string(p.a) + " " + std::to_string(p.b) + "\n";
        text(root / vdir / "pcs.txt", vpcs);
        const int n = v.roi.resolution;
        for (std::size_t k = 0; k < v.layers.size(); ++k) {
          char name[32];
          std::snprintf(name, sizeof name, "layer%02zu.exr", k);
          write_exr(root / vdir / name, n, planes_of(v.layers[k], n));
        }
        views.push_back({{"dir", vdir}, {"view", v.view}, {"resolution", n}, {"a_first", v.a_first},
                         {"epsilon_window", v.epsilon_window}, {"slope", v.slope}, {"layers", v.layers.size()}});
      }
      pairs.push_back({{"dir", dir}, {"a", a}, {"b", b}, {"object_a", r.object_a}, {"object_b", r.object_b},
                       {"epsilon", r.epsilon}, {"colliding", r.colliding.size()}, {"reference", exact.size()},
                       {"views", views}});
    }
    const nlohmann::json meta = {
        {"format", "peelcd.dump/1"},
        {"renderer", stage->renderer() + " (independent writer)"},
        {"gl_version", "none"},
        {"backend", "independent"},
        {"shader_hash", "none"},
        {"options",
         {{"conservative", opt.conservative}, {"theta", opt.theta}, {"phi", opt.phi}, {"roll", opt.roll},
          {"slope", opt.slope}, {"views", opt.views}, {"budget", opt.budget}}},
        {"pairs", pairs}};
    text(root / "meta.json", meta.dump(2) + "\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "independent_dump_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
