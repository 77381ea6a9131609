#pragma once
// How well a scan fits a map at a given pose, for telling a right global-localisation hit from a
// look-alike (map_localizer.hpp): the map's scan endpoints are rasterised once into a grid that
// marks every cell within `fit_distance` of one; a scan's fit at a pose is the fraction of its
// readings whose endpoint falls on a marked cell (the inlier fraction of a likelihood field,
// Thrun, Burgard & Fox, "Probabilistic Robotics", §6.4). A match that fits only half the scan,
// such as a corridor seen the other way round, scores about half; the right pose scores near 1.
// A look-alike corridor elsewhere fits as well, but there some rays pass through mapped walls.
#include <cstdint>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"

namespace polarslam {

/// The endpoints of `scans[i]`'s readings within `max_range`, taken from robot pose `poses[i]`,
/// in the map frame (non-finite ones left out).
std::vector<Vec2> mapEndpoints(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses, double max_range);

/// Throws std::length_error, naming `what`, when a grid `cells_wide` cells across (x, y, before
/// rounding up) at `resolution` m per cell would hold more than `max_cells` (or is not finite):
/// a map that spreads that far is refused rather than exhausting memory.
void requireGridWithin(const Vec2& cells_wide, double resolution, size_t max_cells, const char* what);
/// The localiser's grids' default limit: 410 m × 410 m at 5 cm.
inline constexpr size_t kMaxMapGridCells = size_t{1} << 26;

class MapFitField {
 public:
  /// `scans[i]` taken from robot pose `poses[i]` (map frame); readings beyond `max_range` are
  /// left out. `resolution` in m per cell.
  MapFitField(const std::vector<LaserScan>& scans, const std::vector<Pose2>& poses, double max_range,
              double fit_distance, double resolution = 0.05);
  /// The same from the map's points (mapEndpoints of its scans within `max_range`). Throws
  /// std::length_error when the grid would hold more than `max_cells` (one byte each).
  MapFitField(const std::vector<Vec2>& points, double max_range, double fit_distance, double resolution = 0.05,
              size_t max_cells = kMaxMapGridCells);

  /// Fraction of `scan`'s readings within max_range whose endpoint, with the robot at `pose`,
  /// lies within fit_distance of the map; 0 for a scan with none.
  double fit(const LaserScan& scan, const Pose2& pose) const;
  /// Fraction of the readings whose ray, with the robot at `pose`, passes through the map (enters
  /// and leaves the band around its points for at least `clearance`) before its endpoint, not
  /// counting `clearance` at either end: the scan would see through a wall there. A look-alike place fits its walls but not what lies beyond them.
  double seeThrough(const LaserScan& scan, const Pose2& pose, double clearance) const;

  size_t width() const { return width_; }
  size_t height() const { return height_; }

 private:
  bool near(const Vec2& point) const;

  double max_range_, resolution_;
  Vec2 origin_ = Vec2::Zero();
  size_t width_ = 0, height_ = 0;
  std::vector<uint8_t> near_;
};

}  // namespace polarslam
