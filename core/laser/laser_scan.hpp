#pragma once
// A planar laser scan in the laser's own frame: x forward, y left, bearings counter-clockwise.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

struct LaserScan {
  int64_t utime = 0;            ///< µs, time of beam 0
  int64_t seq = 0;
  double angle_min = 0.0;       ///< rad, bearing of beam 0
  double angle_increment = 0.0; ///< rad
  double time_increment = 0.0;  ///< s between beams
  double range_max = 0.0;       ///< m; ranges >= range_max (or NaN) = no return
  Pose2 laser_pose;             ///< mount pose in the robot base frame
  std::vector<float> ranges;    ///< m

  size_t size() const { return ranges.size(); }
  double bearing(size_t i) const { return angle_min + static_cast<double>(i) * angle_increment; }
  bool valid(size_t i) const {
    const float r = ranges[i];
    return std::isfinite(r) && r > 0.0f && r < range_max;
  }
  Vec2 point(size_t i) const {
    const double b = bearing(i);
    return {ranges[i] * std::cos(b), ranges[i] * std::sin(b)};
  }
};

/// Largest beam count any part of polarslam accepts; bigger scans are rejected as malformed.
inline constexpr size_t kMaxLaserBeams = 20000;

/// Checks a scan's header and sizes. Returns an empty string when usable, otherwise the reason.
/// Individual bad ranges (NaN, negative, huge) are not errors: they count as "no return".
std::string validateScan(const LaserScan& scan);

/// Returns a copy whose bearings increase with index (reverses scans with negative increment)
/// and whose invalid ranges (NaN, <= 0, Inf) are set to +infinity (no return).
LaserScan normalizedScan(const LaserScan& scan);

}  // namespace polarslam
