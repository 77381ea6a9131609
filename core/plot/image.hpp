#pragma once
// Minimal raster images and PNG/PGM output (libpng), written atomically (io/atomic_file.hpp).
#include <cstdint>
#include <string>
#include <vector>

namespace polarslam {

struct Rgb { uint8_t r = 255, g = 255, b = 255; };

struct RgbImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  ///< row-major, row 0 at the top

  RgbImage() = default;
  RgbImage(int w, int h, Rgb fill = {}) : width(w), height(h), pixels(static_cast<size_t>(w) * h, fill) {}
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  Rgb& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
  const Rgb& at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
  void set(int x, int y, Rgb c) { if (inside(x, y)) at(x, y) = c; }
  /// Bresenham line, clipped to the image.
  void line(int x0, int y0, int x1, int y1, Rgb c);
  /// Filled disc of the given radius in pixels.
  void disc(int cx, int cy, int radius, Rgb c);
};

struct GrayImage {
  int width = 0, height = 0;
  std::vector<uint8_t> pixels;  ///< row-major, row 0 at the top
  GrayImage() = default;
  GrayImage(int w, int h, uint8_t fill = 0) : width(w), height(h), pixels(static_cast<size_t>(w) * h, fill) {}
  uint8_t& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
};

/// Writes an 8-bit RGB PNG. Throws std::runtime_error naming the file on failure.
void writePng(const std::string& path, const RgbImage& image);
/// Writes an 8-bit grayscale PNG.
void writePng(const std::string& path, const GrayImage& image);
/// Writes a binary PGM (P5), as the ROS map_server reads.
void writePgm(const std::string& path, const GrayImage& image);
/// Reads an 8-bit PNG back (RGB or gray, converted to RGB) — for tests.
RgbImage readPng(const std::string& path);


}  // namespace polarslam
