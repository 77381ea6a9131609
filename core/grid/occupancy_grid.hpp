#pragma once
// Laser scans ray-cast into a flat 2D raster of log-odds occupancy, one float per cell. It applies
// OctoMap's sensor model and update rules (OcTree::insertPointCloud) without the tree, fast enough
// to rebuild a whole map after every loop closure. `slice()` gives the 2D grid that map_server
// files, pictures and the planner use; `toOcTree()` the OctoMap tree that map.ot / map.bt hold.
//
//   OccupancyGrid grid = buildGrid(scans, poses, GridOptions{.resolution = 0.05});
//   GridSlice cells = grid.slice();
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "grid/grid_slice.hpp"
#include "laser/laser_scan.hpp"

namespace octomap {
class OcTree;
}

namespace polarslam {

struct GridOptions {
  double resolution = 0.05;     ///< m, cell edge
  double max_range = 0.0;       ///< m: longer beams only clear space up to it; 0 = the scan's range_max
  double prob_hit = 0.7;        ///< sensor model: P(occupied | hit), log-odds +0.85
  double prob_miss = 0.4;       ///< P(occupied | ray passed), log-odds −0.41
  double clamp_min = 0.12, clamp_max = 0.97;  ///< log-odds clamping (keeps the map able to change)
  double occupied_threshold = 0.65;  ///< P above which a cell counts as occupied (exports, planner)
  double free_threshold = 0.196;     ///< P below which a cell counts as free
  /// Largest raster, 8 bytes per cell (the default: 1 GiB, 580 m × 580 m at 5 cm); scans spreading
  /// wider make insertScan throw.
  size_t max_cells = size_t{1} << 27;
};

class OccupancyGrid {
 public:
  /// Throws std::invalid_argument for a resolution that is not positive or a sensor model with
  /// probabilities outside (0, 1) or clamp_min > clamp_max.
  explicit OccupancyGrid(const GridOptions& options = {});

  /// Ray-casts one scan taken with the robot base at `robot_pose` (map frame), with the rules of
  /// OctoMap's insertPointCloud(cloud, sensor, max_range): the cells a beam crosses (its end cell
  /// excluded) are free, the end cells of beams within max_range occupied; a beam longer than
  /// max_range only clears up to there; a cell both free and occupied in one scan counts occupied;
  /// each cell gets at most one update per scan. Beams without a return are skipped (a missing
  /// return says nothing reliable: glass, black surfaces). Throws std::length_error when the
  /// scan would grow the raster beyond options().max_cells.
  void insertScan(const LaserScan& scan, const Pose2& robot_pose);
  /// Sizes the raster once for everything these scans can touch, instead of growing it as they
  /// arrive (buildGrid calls it). Throws std::length_error as insertScan does.
  void reserve(const std::vector<const LaserScan*>& scans, const std::vector<Pose2>& poses);
  /// Nothing left to do: the raster is current after every insertScan (kept for callers written
  /// for the OcTree, which updated its inner nodes here).
  void finishUpdates() {}

  /// The 2D layer, bounded by the observed cells.
  GridSlice slice() const;
  /// The same cells as an OctoMap tree (the layer at layerZ(), same sensor model and clamping),
  /// inner nodes updated and pruned: what map.ot and map.bt hold.
  std::unique_ptr<octomap::OcTree> toOcTree() const;

  const GridOptions& options() const { return options_; }
  size_t scansInserted() const { return scans_inserted_; }
  /// z of the centres of the voxel layer the cells form in toOcTree().
  double layerZ() const { return 0.5 * options_.resolution; }

 private:
  /// Cells by map-frame index: cell (ix, iy) covers [ix, ix + 1) × [iy, iy + 1) resolutions.
  struct CellBox {
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  ///< inclusive; empty when x1 < x0

    bool empty() const { return x1 < x0 || y1 < y0; }
    bool contains(const CellBox& b) const { return b.x0 >= x0 && b.y0 >= y0 && b.x1 <= x1 && b.y1 <= y1; }
    int64_t width() const { return empty() ? 0 : int64_t{x1} - x0 + 1; }
    int64_t height() const { return empty() ? 0 : int64_t{y1} - y0 + 1; }
    void add(int x, int y);
    void add(const CellBox& b);
  };
  /// A map-frame point in fixed point: cells × 2^16. Exact integer ray walking.
  struct FixedPoint {
    int64_t x = 0, y = 0;
  };
  struct Beam {
    FixedPoint end;
    bool hit;  ///< within max_range: its end cell is occupied
  };
  /// One scan ready to cast: the sensor, the beams (in beams_) and the cells they can touch.
  struct ScanPlan {
    FixedPoint sensor;
    bool rays = false;  ///< false when the sensor lies outside OctoMap's key range (no rays, as there)
    CellBox reach;
  };
  struct Cell {
    float log_odds = 0.0f;
    uint32_t stamp = 0;  ///< the last scan that updated the cell; 0 = never observed
  };
  /// OctoMap's updateNodeLogOdds (float addition, then clamping), once per scan. A value, so
  /// that ray walking keeps it in registers.
  struct CellUpdate {
    float delta, clamp_min, clamp_max;
    uint32_t stamp;
    void operator()(Cell& cell) const {
      if (cell.stamp == stamp) return;
      cell.log_odds = std::min(std::max(cell.log_odds + delta, clamp_min), clamp_max);
      cell.stamp = stamp;
    }
  };

  ScanPlan planScan(const LaserScan& scan, const Pose2& robot_pose);
  const std::vector<Vec2>& beamDirections(const LaserScan& scan);
  void growToContain(const CellBox& box, bool with_margin);
  size_t indexOf(int ix, int iy) const;
  CellUpdate updateFor(float delta) const { return {delta, clamp_min_, clamp_max_, stamp_}; }
  void clearRay(const FixedPoint& from, FixedPoint to);

  GridOptions options_;
  float hit_delta_, miss_delta_, clamp_min_, clamp_max_;  ///< log-odds, as OctoMap stores them
  CellBox bounds_;    ///< the cells the raster holds
  CellBox observed_;  ///< the cells updated so far
  std::vector<Cell> cells_;  ///< row-major over bounds_, row 0 at the lowest y
  uint32_t stamp_ = 0;
  size_t scans_inserted_ = 0;
  // Per-scan scratch, kept to avoid reallocating.
  std::vector<Beam> beams_;
  std::vector<Vec2> directions_;  ///< unit vector of every beam in the laser frame
  double directions_angle_min_ = 0.0, directions_increment_ = 0.0;
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
