#pragma once
// Grid outputs, each written atomically (temp file + rename, so a crash never leaves a
// half-written map): map.ot (full probabilities), map.bt (OctoMap's compact maximum-likelihood
// form), map.pgm + map.yaml (ROS map_server format) and map.png (for people).
#include <string>
#include <vector>

#include "grid/occupancy_grid.hpp"
#include "plot/plot.hpp"

namespace polarslam {

/// What map.png shows on top of the grid.
struct GridPicture {
  std::string title = "occupancy grid";
  std::vector<PlotSeries> paths;      ///< e.g. the regenerated trajectory
  std::vector<PlotSegment> segments;  ///< e.g. SLAM map lines
};

struct GridFiles {
  std::string ot, bt, pgm, yaml, png;
};

/// map_server values: occupied 0, free 254, unknown 205 (trinary, as map_saver writes them).
/// Row 0 of the image is the highest y.
GrayImage toMapServerImage(const GridSlice& slice);
/// The map_server YAML text for `image_file` (a name relative to the YAML's folder).
std::string mapServerYaml(const GridSlice& slice, const std::string& image_file);
/// Colour picture of the slice: occupied black, free white, unknown grey. Row 0 = highest y.
RgbImage gridPicture(const GridSlice& slice);

/// Writes all five files into `dir` (created if missing) with the given base name.
/// Throws std::runtime_error naming the file on failure.
GridFiles writeGridFiles(const std::string& dir, const OccupancyGrid& grid, const GridPicture& picture = {},
                         const std::string& base_name = "map");
/// Same, from an already computed slice (saves recomputing it).
GridFiles writeGridFiles(const std::string& dir, const OccupancyGrid& grid, const GridSlice& slice,
                         const GridPicture& picture, const std::string& base_name = "map");

}  // namespace polarslam
