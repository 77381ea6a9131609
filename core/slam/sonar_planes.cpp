#include "slam/sonar_planes.hpp"

#include <cmath>

namespace polarslam {

std::vector<SonarPlane> sonarPlanes(const SonarScan& scan) {
  std::vector<SonarPlane> planes;
  for (const SonarTarget& t : scan.targets) {
    if (t.kind != SonarKind::Plane || !std::isfinite(t.range) || !std::isfinite(t.bearing) || t.range <= 0.0 ||
        t.range > scan.range_max)
      continue;
    const double angle = scan.sensor_pose.theta + t.bearing;
    const Vec2 normal(std::cos(angle), std::sin(angle));
    planes.push_back({scan.sensor_pose.translation() + t.range * normal, normal});
  }
  return planes;
}

SonarPlane movedPlane(const SonarPlane& plane, const Pose2& motion) {
  const double c = std::cos(motion.theta), s = std::sin(motion.theta);
  const Vec2 normal(c * plane.normal.x() + s * plane.normal.y(), -s * plane.normal.x() + c * plane.normal.y());
  return {motion.inverseTransform(plane.foot), normal};
}

std::vector<SonarPlane> repeatedPlanes(const std::vector<SonarPlane>& now, const std::vector<SonarPlane>& before,
                                       const SonarPlaneFillOptions& options) {
  std::vector<SonarPlane> repeated;
  for (const SonarPlane& p : now)
    for (const SonarPlane& q : before) {
      const double turn = std::atan2(p.normal.x() * q.normal.y() - p.normal.y() * q.normal.x(), p.normal.dot(q.normal));
      // The foot moves along the wall with the robot: compare the lines, not the feet.
      if (std::abs(turn) <= options.repeat_angle && std::abs(p.normal.dot(q.foot - p.foot)) <= options.repeat_distance) {
        repeated.push_back(p);
        break;
      }
    }
  return repeated;
}

namespace {

/// Range at which beam i meets the plane within half_extent of its foot point, or NaN.
double rangeToPlane(const LaserScan& scan, size_t i, const SonarPlane& plane, double half_extent) {
  const double angle = scan.laser_pose.theta + scan.bearing(i);
  const Vec2 direction(std::cos(angle), std::sin(angle));
  const double facing = plane.normal.dot(direction);
  if (facing <= 1e-3) return std::nan("");  // the beam runs along or away from the wall
  const Vec2 origin = scan.laser_pose.translation();
  const double range = plane.normal.dot(plane.foot - origin) / facing;
  if (!(range > 0.0) || range >= scan.range_max) return std::nan("");
  if ((origin + range * direction - plane.foot).norm() > half_extent) return std::nan("");
  return range;
}

}  // namespace

bool laserSeesLittle(const LaserScan& scan, double max_range, const SonarPlaneFillOptions& options) {
  size_t returns = 0;
  for (size_t i = 0; i < scan.size(); ++i)
    if (scan.valid(i) && scan.ranges[i] <= max_range) ++returns;
  return static_cast<double>(returns) < options.max_return_fraction * static_cast<double>(scan.size());
}

size_t fillFromSonarPlanes(LaserScan& scan, const std::vector<SonarPlane>& planes, const SonarPlaneFillOptions& options) {
  size_t filled = 0;
  for (const SonarPlane& plane : planes) {
    // Laser-aided sonar selection (thesis §3.3.1): a wall the laser sees itself is no glass; the
    // sonar's plane would only paint over its doors and gaps.
    std::vector<std::pair<size_t, double>> beams;
    size_t seen = 0;
    for (size_t i = 0; i < scan.size(); ++i) {
      const double range = rangeToPlane(scan, i, plane, options.half_extent);
      if (std::isnan(range)) continue;
      beams.emplace_back(i, range);
      if (scan.valid(i) && std::abs(scan.ranges[i] - range) <= options.margin) ++seen;
    }
    if (beams.empty() || static_cast<double>(seen) > options.laser_seen_fraction * static_cast<double>(beams.size()))
      continue;
    for (const auto& [i, range] : beams) {
      if (scan.valid(i) && scan.ranges[i] <= range + options.margin) continue;  // something nearer than the wall
      scan.ranges[i] = static_cast<float>(range);
      ++filled;
    }
  }
  return filled;
}

}  // namespace polarslam
