#pragma once
// The 2D occupancy layer that map_server files, pictures, the planner and grid_map_t messages
// use: one probability per cell. Plain data, no OctoMap, so the LCM bridge can take it too.
#include <cmath>
#include <cstddef>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Occupancy probability per cell, NaN where nothing was observed.
struct GridSlice {
  double resolution = 0.05;
  Vec2 origin = Vec2::Zero();  ///< map-frame corner of cell (0, 0) (lowest x and y)
  int width = 0, height = 0;   ///< cells along x and y
  std::vector<float> probability;  ///< row-major, row 0 at the lowest y
  double occupied_threshold = 0.65, free_threshold = 0.196;

  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
  size_t index(int ix, int iy) const { return static_cast<size_t>(iy) * static_cast<size_t>(width) + ix; }
  float at(int ix, int iy) const { return probability[index(ix, iy)]; }
  bool known(int ix, int iy) const { return !std::isnan(at(ix, iy)); }
  bool occupied(int ix, int iy) const { return known(ix, iy) && at(ix, iy) >= occupied_threshold; }
  bool free(int ix, int iy) const { return known(ix, iy) && at(ix, iy) <= free_threshold; }
  Vec2 cellCenter(int ix, int iy) const { return origin + resolution * Vec2(ix + 0.5, iy + 0.5); }
  /// Cell containing a map-frame point (may be outside the slice).
  void cellOf(const Vec2& p, int& ix, int& iy) const {
    ix = static_cast<int>(std::floor((p.x() - origin.x()) / resolution));
    iy = static_cast<int>(std::floor((p.y() - origin.y()) / resolution));
  }
  Vec2 extentMax() const { return origin + resolution * Vec2(width, height); }
};

}  // namespace polarslam
