#pragma once
// Laser scans ray-cast into an OctoMap OcTree (log-odds occupancy). polarslam maps are 2D: every
// ray lies in one z layer of voxels, so the tree is a quadtree in effect, and `slice()` gives
// the plain 2D grid that map_server files, pictures and the planner use.
//
//   OccupancyGrid grid = buildGrid(scans, poses, GridOptions{.resolution = 0.05});
//   GridSlice cells = grid.slice();
#include <octomap/OcTree.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include "laser/laser_scan.hpp"

namespace polarslam {

struct GridOptions {
  double resolution = 0.05;     ///< m, voxel edge
  double max_range = 0.0;       ///< m: longer beams only clear space up to it; 0 = the scan's range_max
  double prob_hit = 0.7;        ///< sensor model: P(occupied | hit), log-odds +0.85
  double prob_miss = 0.4;       ///< P(occupied | ray passed), log-odds −0.41
  double clamp_min = 0.12, clamp_max = 0.97;  ///< log-odds clamping (keeps the map able to change)
  double occupied_threshold = 0.65;  ///< P above which a cell counts as occupied (exports, planner)
  double free_threshold = 0.196;     ///< P below which a cell counts as free
};

/// The 2D layer: occupancy probability per cell, NaN where nothing was observed.
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

class OccupancyGrid {
 public:
  explicit OccupancyGrid(const GridOptions& options = {});
  OccupancyGrid(const OccupancyGrid& other);
  OccupancyGrid& operator=(const OccupancyGrid& other);
  OccupancyGrid(OccupancyGrid&&) noexcept = default;
  OccupancyGrid& operator=(OccupancyGrid&&) noexcept = default;

  /// Ray-casts one scan taken with the robot base at `robot_pose` (map frame). Beams without a
  /// return are skipped (a missing return says nothing reliable: glass, black surfaces).
  void insertScan(const LaserScan& scan, const Pose2& robot_pose);
  /// Brings inner nodes up to date after insertions (buildGrid does it; call after insertScan).
  void finishUpdates();

  /// The 2D layer, bounded by the observed cells.
  GridSlice slice() const;

  const octomap::OcTree& tree() const { return *tree_; }
  octomap::OcTree& tree() { return *tree_; }
  const GridOptions& options() const { return options_; }
  size_t scansInserted() const { return scans_inserted_; }
  /// z of the centres of the voxel layer every ray lies in.
  double layerZ() const { return 0.5 * options_.resolution; }

 private:
  GridOptions options_;
  std::unique_ptr<octomap::OcTree> tree_;
  size_t scans_inserted_ = 0;
  bool dirty_ = false;
};

/// The 2D layer at height z of any occupancy tree (e.g. one read back from map.bt), bounded by
/// its observed cells.
GridSlice sliceOf(const octomap::OcTree& tree, double z, double occupied_threshold = 0.65,
                  double free_threshold = 0.196);

/// Builds a grid from scans and the robot base pose of each (same length; map frame). Any
/// pipeline can call it with its own poses: scan-time SLAM poses, regenerated poses, PSM-SLAM
/// poses, ground truth.
OccupancyGrid buildGrid(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses,
                        const GridOptions& options = {});
OccupancyGrid buildGrid(const std::vector<const LaserScan*>& scans, const std::vector<Pose2>& poses,
                        const GridOptions& options = {});

}  // namespace polarslam
