// EXR layers (OpenEXR), PNG previews (libpng).
#include "peelcd/io/error.h"
#include "peelcd/oracle/dump.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

namespace peelcd::oracle {
namespace {

// The five EXR channels of a layer, planar, rows top to bottom.
struct Planes {
  std::vector<float> z, dzdx, dzdy;
  std::vector<std::uint32_t> id, object;
  explicit Planes(std::size_t count) : z(count), dzdx(count), dzdy(count), id(count), object(count) {}
};

using texel::as_float;
std::uint32_t as_bits(float f) {
  std::uint32_t w;
  std::memcpy(&w, &f, 4);
  return w;
}

}  // namespace

void write_layer_exr(const std::string& path, const std::vector<std::uint32_t>& layer, int n) {
  const std::size_t count = std::size_t(n) * n;
  Planes p(count);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::size_t src = std::size_t(n - 1 - y) * n + x, dst = std::size_t(y) * n + x;
      p.z[dst] = as_float(layer[4 * src]);
      p.id[dst] = layer[4 * src + 1] & 0x7fffffffu;
      p.object[dst] = layer[4 * src + 1] >> 31;
      p.dzdx[dst] = as_float(layer[4 * src + 2]);
      p.dzdy[dst] = as_float(layer[4 * src + 3]);
    }
  try {
    Imf::Header header(n, n);
    header.compression() = Imf::ZIP_COMPRESSION;  // lossless
    header.insert("peelcd", Imf::StringAttribute("peel layer: Z = window depth, id = ID + 1 (0 = empty), "
                                                 "object = 0 (A) / 1 (B), dzdx/dzdy = depth slope per texel"));
    header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    header.channels().insert("id", Imf::Channel(Imf::UINT));
    header.channels().insert("object", Imf::Channel(Imf::UINT));
    header.channels().insert("dzdx", Imf::Channel(Imf::FLOAT));
    header.channels().insert("dzdy", Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer fb;
    const std::size_t row = sizeof(float) * n;
    fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(p.z.data()), sizeof(float), row));
    fb.insert("id", Imf::Slice(Imf::UINT, reinterpret_cast<char*>(p.id.data()), sizeof(std::uint32_t), row));
    fb.insert("object", Imf::Slice(Imf::UINT, reinterpret_cast<char*>(p.object.data()), sizeof(std::uint32_t), row));
    fb.insert("dzdx", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(p.dzdx.data()), sizeof(float), row));
    fb.insert("dzdy", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(p.dzdy.data()), sizeof(float), row));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(n);
  } catch (const std::exception& e) {
    throw InputError("peelcd: cannot write '" + path + "': " + e.what());
  }
}

std::vector<std::uint32_t> read_layer_exr(const std::string& path, int& n) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    if (w != h || w <= 0) throw InputError("peelcd: '" + path + "' is not a square layer");
    for (const char* ch : {"Z", "id", "object", "dzdx", "dzdy"})
      if (!file.header().channels().findChannel(ch))
        throw InputError("peelcd: '" + path + "' has no channel " + ch + " (not a peelcd layer)");
    n = w;
    const std::size_t count = std::size_t(n) * n;
    Planes p(count);
    Imf::FrameBuffer fb;
    const std::size_t row = sizeof(float) * n;
    const auto base = [&](auto* data) {
      return reinterpret_cast<char*>(data) - (std::ptrdiff_t(dw.min.x) + std::ptrdiff_t(dw.min.y) * n) * 4;
    };
    fb.insert("Z", Imf::Slice(Imf::FLOAT, base(p.z.data()), sizeof(float), row));
    fb.insert("id", Imf::Slice(Imf::UINT, base(p.id.data()), sizeof(std::uint32_t), row));
    fb.insert("object", Imf::Slice(Imf::UINT, base(p.object.data()), sizeof(std::uint32_t), row));
    fb.insert("dzdx", Imf::Slice(Imf::FLOAT, base(p.dzdx.data()), sizeof(float), row));
    fb.insert("dzdy", Imf::Slice(Imf::FLOAT, base(p.dzdy.data()), sizeof(float), row));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    std::vector<std::uint32_t> layer(count * 4);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t src = std::size_t(y) * n + x, dst = std::size_t(n - 1 - y) * n + x;
        layer[4 * dst] = as_bits(p.z[src]);
        layer[4 * dst + 1] = p.id[src] == 0 ? 0u : ((p.object[src] & 1u) << 31) | (p.id[src] & 0x7fffffffu);
        layer[4 * dst + 2] = as_bits(p.dzdx[src]);
        layer[4 * dst + 3] = as_bits(p.dzdy[src]);
      }
    return layer;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError("peelcd: cannot read '" + path + "': " + e.what());
  }
}

namespace {
void png_append(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}
void png_no_flush(png_structp) {}
}  // namespace

std::vector<std::uint8_t> encode_png(const Rgb& image) {
  std::vector<std::uint8_t> out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, &info);
    throw InputError("peelcd: libpng could not start a PNG");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw InputError("peelcd: libpng failed to encode a PNG");
  }
  png_set_write_fn(png, &out, png_append, png_no_flush);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_bytep>(&image.pixels[std::size_t(y) * image.width * 3]));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

void write_png(const std::string& path, const Rgb& image) {
  const std::vector<std::uint8_t> bytes = encode_png(image);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw InputError("peelcd: cannot write '" + path + "'");
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (std::fclose(f) != 0 || !ok) throw InputError("peelcd: cannot write '" + path + "'");
}

Rgb layer_preview(const std::vector<std::uint32_t>& layer, int n, const std::vector<bool>& marks) {
  Rgb img(2 * n, n);
  float lo = std::numeric_limits<float>::max(), hi = -lo;
  const std::size_t count = std::size_t(n) * n;
  for (std::size_t t = 0; t < count; ++t)
    if (!texel_empty(layer, t)) {
      lo = std::min(lo, as_float(layer[4 * t]));
      hi = std::max(hi, as_float(layer[4 * t]));
    }
  const float range = hi > lo ? hi - lo : 1.0f;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::size_t t = std::size_t(n - 1 - y) * n + x;
      if (!marks.empty() && marks[t]) {
        img.set(x, y, {255, 0, 255});
        img.set(n + x, y, {255, 0, 255});
        continue;
      }
      if (texel_empty(layer, t)) {
        img.set(x, y, {24, 24, 40});
        img.set(n + x, y, {24, 24, 40});
        continue;
      }
      // Depth: near = bright, stretched over this layer's range.
      const float z = (as_float(layer[4 * t]) - lo) / range;
      const auto g = std::uint8_t(std::lround(235.0f - 175.0f * z));
      img.set(x, y, {g, g, g});
      // IDs: a hash of (object, ID) to a colour; object A warm, object B cool.
      std::uint32_t h = layer[4 * t + 1] * 2654435761u;
      h ^= h >> 15;
      h *= 2246822519u;
      h ^= h >> 13;
      const std::uint8_t r = 90 + (h & 0x7f), gg = 90 + ((h >> 8) & 0x7f), b = 90 + ((h >> 16) & 0x7f);
      if (texel_object(layer, t) == 0) img.set(n + x, y, {std::uint8_t(std::min(255, r + 40)), gg, std::uint8_t(b / 2)});
      else img.set(n + x, y, {std::uint8_t(r / 2), gg, std::uint8_t(std::min(255, b + 40))});
    }
  return img;
}

}  // namespace peelcd::oracle
