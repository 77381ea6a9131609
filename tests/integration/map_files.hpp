#pragma once
// The standard 2D map files (map.yaml + map.pgm, as map_server reads them) compared cell by cell.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace polarslam::testing {

/// A map_server map (map.yaml + map.pgm): occupied cells as map-frame cell indices.
struct MapServerMap {
  double resolution = 0.0;
  std::set<std::pair<long, long>> occupied;
};

inline MapServerMap readMapServer(const std::filesystem::path& dir) {
  MapServerMap map;
  const YAML::Node yaml = YAML::LoadFile((dir / "map.yaml").string());
  map.resolution = yaml["resolution"].as<double>();
  const double ox = yaml["origin"][0].as<double>(), oy = yaml["origin"][1].as<double>();
  std::ifstream pgm(dir / yaml["image"].as<std::string>(), std::ios::binary);
  std::string magic;
  int width = 0, height = 0, max_value = 0;
  pgm >> magic >> width >> height >> max_value;
  pgm.get();
  std::vector<unsigned char> pixels(static_cast<size_t>(width) * height);
  pgm.read(reinterpret_cast<char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
  if (magic != "P5" || !pgm) return {};
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col)
      if (pixels[static_cast<size_t>(row) * width + col] == 0)  // row 0 is the highest y
        map.occupied.insert({std::lround(ox / map.resolution) + col, std::lround(oy / map.resolution) + height - 1 - row});
  return map;
}

/// Fraction of `a`'s occupied cells that are occupied in `b` too.
inline double occupiedAgreement(const MapServerMap& a, const MapServerMap& b) {
  if (a.occupied.empty()) return 0.0;
  long shared = 0;
  for (const auto& cell : a.occupied) shared += b.occupied.count(cell);
  return static_cast<double>(shared) / static_cast<double>(a.occupied.size());
}

}  // namespace polarslam::testing
