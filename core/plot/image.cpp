#include "plot/image.hpp"

#include "io/atomic_file.hpp"

#include <png.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace polarslam {
namespace {

struct FileCloser { void operator()(FILE* f) const { if (f) std::fclose(f); } };

void writePngRows(const std::string& path, int width, int height, int color_type,
                  const uint8_t* data, size_t row_bytes) {
  const std::string tmp = temporaryPathFor(path);
  std::unique_ptr<FILE, FileCloser> file(std::fopen(tmp.c_str(), "wb"));
  if (!file) throw std::runtime_error("cannot write '" + path + "'");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) throw std::runtime_error("libpng: out of memory writing '" + path + "'");
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng: failed writing '" + path + "'");
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y)
    png_write_row(png, const_cast<png_bytep>(data + static_cast<size_t>(y) * row_bytes));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  file.reset();
  commitTemporary(tmp, path);
}

}  // namespace

void RgbImage::line(int x0, int y0, int x1, int y1, Rgb c) {
  const int dx = std::abs(x1 - x0), sx = x0 < x1 ? 1 : -1;
  const int dy = -std::abs(y1 - y0), sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  for (int guard = 0; guard < 100000; ++guard) {
    set(x0, y0, c);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) { err += dy; x0 += sx; }
    if (e2 <= dx) { err += dx; y0 += sy; }
  }
}

void RgbImage::disc(int cx, int cy, int radius, Rgb c) {
  for (int y = -radius; y <= radius; ++y)
    for (int x = -radius; x <= radius; ++x)
      if (x * x + y * y <= radius * radius) set(cx + x, cy + y, c);
}

void writePng(const std::string& path, const RgbImage& image) {
  static_assert(sizeof(Rgb) == 3);
  writePngRows(path, image.width, image.height, PNG_COLOR_TYPE_RGB,
               reinterpret_cast<const uint8_t*>(image.pixels.data()), static_cast<size_t>(image.width) * 3);
}

void writePng(const std::string& path, const GrayImage& image) {
  writePngRows(path, image.width, image.height, PNG_COLOR_TYPE_GRAY, image.pixels.data(),
               static_cast<size_t>(image.width));
}

void writePgm(const std::string& path, const GrayImage& image) {
  std::string content = "P5\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  content.append(reinterpret_cast<const char*>(image.pixels.data()), image.pixels.size());
  writeFileAtomically(path, content);
}

RgbImage readPng(const std::string& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str()))
    throw std::runtime_error("cannot read PNG '" + path + "'");
  img.format = PNG_FORMAT_RGB;
  RgbImage out(static_cast<int>(img.width), static_cast<int>(img.height));
  if (!png_image_finish_read(&img, nullptr, out.pixels.data(), 0, nullptr))
    throw std::runtime_error("cannot decode PNG '" + path + "'");
  return out;
}

}  // namespace polarslam
