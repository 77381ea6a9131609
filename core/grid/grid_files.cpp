#include "grid/grid_files.hpp"

#include <fcntl.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.hpp"
#include "plot/image.hpp"

namespace polarslam {
namespace {

constexpr uint8_t kOccupiedValue = 0, kFreeValue = 254, kUnknownValue = 205;

std::string formatNumber(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

/// Debian's liboctomap is built with its debug messages on: serialising a tree prints "Writing N
/// nodes ... done." on standard error. This sends file descriptor 2 to /dev/null for its lifetime.
class SilencedStderr {
 public:
  SilencedStderr() {
    std::fflush(stderr);
    saved_ = dup(STDERR_FILENO);
    const int null_fd = open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null_fd >= 0) dup2(null_fd, STDERR_FILENO);
    if (null_fd >= 0) close(null_fd);
  }
  ~SilencedStderr() {
    std::fflush(stderr);
    if (saved_ < 0) return;
    dup2(saved_, STDERR_FILENO);
    close(saved_);
  }
  SilencedStderr(const SilencedStderr&) = delete;
  SilencedStderr& operator=(const SilencedStderr&) = delete;

 private:
  int saved_ = -1;
};

/// map.ot (full probabilities) and map.bt (maximum likelihood). writeBinary converts the tree it
/// writes in place, so the .ot goes first.
void writeOctrees(const std::string& ot_path, const std::string& bt_path, octomap::OcTree& tree) {
  std::ostringstream ot(std::ios::binary), bt(std::ios::binary);
  bool written = false;
  {
    const SilencedStderr quiet;
    written = tree.write(ot) && ot && tree.writeBinary(bt) && bt;
  }
  if (!written) throw std::runtime_error("cannot serialise the octrees for '" + ot_path + "' and '" + bt_path + "'");
  writeFileAtomically(ot_path, ot.str());
  writeFileAtomically(bt_path, bt.str());
}

}  // namespace

GrayImage toMapServerImage(const GridSlice& slice) {
  GrayImage image(slice.width, slice.height, kUnknownValue);
  for (int iy = 0; iy < slice.height; ++iy)
    for (int ix = 0; ix < slice.width; ++ix) {
      uint8_t& pixel = image.at(ix, slice.height - 1 - iy);
      if (slice.occupied(ix, iy)) pixel = kOccupiedValue;
      else if (slice.free(ix, iy)) pixel = kFreeValue;
    }
  return image;
}

std::string mapServerYaml(const GridSlice& slice, const std::string& image_file) {
  std::ostringstream y;
  y << "image: " << image_file << "\n"
    << "resolution: " << formatNumber(slice.resolution) << "\n"
    << "origin: [" << formatNumber(slice.origin.x()) << ", " << formatNumber(slice.origin.y()) << ", 0.0]\n"
    << "negate: 0\n"
    << "occupied_thresh: " << formatNumber(slice.occupied_threshold) << "\n"
    << "free_thresh: " << formatNumber(slice.free_threshold) << "\n"
    << "mode: trinary\n";
  return y.str();
}

RgbImage gridPicture(const GridSlice& slice) {
  RgbImage image(slice.width, slice.height, Rgb{190, 190, 190});
  for (int iy = 0; iy < slice.height; ++iy)
    for (int ix = 0; ix < slice.width; ++ix) {
      if (!slice.known(ix, iy)) continue;
      const double p = slice.at(ix, iy);
      const auto v = static_cast<uint8_t>(std::lround(255.0 * (1.0 - p)));
      Rgb c{v, v, v};
      if (slice.occupied(ix, iy)) c = Rgb{0, 0, 0};
      else if (slice.free(ix, iy)) c = Rgb{255, 255, 255};
      image.at(ix, slice.height - 1 - iy) = c;
    }
  return image;
}

GridFiles writeGridFiles(const std::string& dir, const OccupancyGrid& grid, const GridSlice& observed,
                         const GridPicture& picture, const std::string& base_name) {
  GridSlice slice = observed;
  if (slice.width == 0 || slice.height == 0) {  // nothing observed yet: one unknown cell
    slice.width = slice.height = 1;
    slice.probability.assign(1, std::numeric_limits<float>::quiet_NaN());
  }
  std::filesystem::create_directories(dir);
  const std::filesystem::path d(dir);
  GridFiles files;
  files.ot = (d / (base_name + ".ot")).string();
  files.bt = (d / (base_name + ".bt")).string();
  files.pgm = (d / (base_name + ".pgm")).string();
  files.yaml = (d / (base_name + ".yaml")).string();
  files.png = (d / (base_name + ".png")).string();
  writeOctrees(files.ot, files.bt, *grid.toOcTree());
  // The image first: a reader that sees the new YAML finds the image it names complete.
  writePgm(files.pgm, toMapServerImage(slice));
  writeFileAtomically(files.yaml, mapServerYaml(slice, base_name + ".pgm"));

  Plot plot;
  plot.title = picture.title;
  plot.background = gridPicture(slice);
  plot.image_min = slice.origin;
  plot.image_max = slice.extentMax();
  plot.series = picture.paths;
  plot.segments = picture.segments;
  writePlotPng(files.png, plot);
  return files;
}

GridFiles writeGridFiles(const std::string& dir, const OccupancyGrid& grid, const GridPicture& picture,
                         const std::string& base_name) {
  return writeGridFiles(dir, grid, grid.slice(), picture, base_name);
}

}  // namespace polarslam
