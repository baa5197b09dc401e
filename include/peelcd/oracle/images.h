#pragma once
// The oracle's images: layers as lossless EXR (the dump format, peelcd/oracle/format.h), 8-bit
// previews as PNG.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace peelcd::oracle {

// Writes one layer as EXR (see the layout above); reads it back into N*N*4 words. Throw InputError.
void write_layer_exr(const std::string& path, const std::vector<std::uint32_t>& layer, int n);
std::vector<std::uint32_t> read_layer_exr(const std::string& path, int& n);
// An 8-bit RGB image, rows top to bottom, written as PNG. Throws InputError.
struct Rgb {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // width * height * 3
  Rgb(int w, int h) : width(w), height(h), pixels(std::size_t(w) * h * 3, 0) {}
  void set(int x, int y, std::array<std::uint8_t, 3> c) {
    std::uint8_t* p = &pixels[(std::size_t(y) * width + x) * 3];
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  }
};
void write_png(const std::string& path, const Rgb& image);
std::vector<std::uint8_t> encode_png(const Rgb& image);
// The preview of one layer: depth in grey (near = bright) | IDs in a stable palette, with the
// texels in `marks` (may be empty) in magenta on both halves.
Rgb layer_preview(const std::vector<std::uint32_t>& layer, int n, const std::vector<bool>& marks);

}  // namespace peelcd::oracle
