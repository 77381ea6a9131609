#include "laser/laser_scan.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace polarslam {

std::string validateScan(const LaserScan& scan) {
  if (scan.ranges.empty()) return "empty scan";
  if (scan.ranges.size() > kMaxLaserBeams)
    return "too many beams (" + std::to_string(scan.ranges.size()) + " > " + std::to_string(kMaxLaserBeams) + ")";
  if (!std::isfinite(scan.angle_min) || !std::isfinite(scan.angle_increment) ||
      scan.angle_increment == 0.0)
    return "invalid angle_min/angle_increment";
  const double fov = std::abs(scan.angle_increment) * static_cast<double>(scan.ranges.size() - 1);
  if (fov > 2.0 * std::numbers::pi + 1e-6) return "field of view over 360 degrees";
  if (!(scan.range_max > 0.0) || !std::isfinite(scan.range_max)) return "invalid range_max";
  if (!std::isfinite(scan.time_increment) || scan.time_increment < 0.0 || scan.time_increment > 1.0)
    return "invalid time_increment";
  return {};
}

LaserScan normalizedScan(const LaserScan& scan) {
  LaserScan out = scan;
  constexpr float kNoReturn = std::numeric_limits<float>::infinity();
  for (float& r : out.ranges)
    if (!std::isfinite(r) || r <= 0.0f || r >= scan.range_max) r = kNoReturn;
  if (out.angle_increment < 0.0 && !out.ranges.empty()) {
    std::reverse(out.ranges.begin(), out.ranges.end());
    out.angle_min = scan.bearing(scan.ranges.size() - 1);
    out.angle_increment = -scan.angle_increment;
    // beam 0 is now the last one measured; time_increment keeps its magnitude
    out.utime = scan.utime;
  }
  return out;
}

}  // namespace polarslam
