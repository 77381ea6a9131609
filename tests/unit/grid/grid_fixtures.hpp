#pragma once
// Test fixtures for the grid module: small worlds and exact (noise-free) laser scans cast in
// them with the simulator's ray caster, so the walls are an independent truth.
#include <cmath>
#include <numbers>
#include <vector>

#include "grid/occupancy_grid.hpp"
#include "laser/laser_scan.hpp"
#include "sim/world.hpp"

namespace polarslam::test {

/// A 6 m × 4 m room, x ∈ [0, 6], y ∈ [0, 4], split by a wall at x = 3 with a 1.2 m doorway
/// (y ∈ [1.4, 2.6]); everything moved by a fraction of a cell so no wall lies on a cell border.
inline World twoRoomWorld() {
  const Vec2 o(0.013, 0.021);
  World w;
  w.addPolyline({o + Vec2(0, 0), o + Vec2(6, 0), o + Vec2(6, 4), o + Vec2(0, 4)}, {Material::Wall}, true, "outer");
  w.addPolyline({o + Vec2(3, 0), o + Vec2(3, 1.4)}, {Material::Wall}, false, "wall low");
  w.addPolyline({o + Vec2(3, 2.6), o + Vec2(3, 4)}, {Material::Wall}, false, "wall high");
  return w;
}

/// A noise-free scan from `robot` (base pose in the world), laser mounted 0.2 m ahead.
inline LaserScan castScan(const World& world, const Pose2& robot, int beams = 361, double fov = 2 * std::numbers::pi,
                          int64_t utime = 0) {
  LaserScan scan;
  scan.utime = utime;
  scan.range_max = 8.0;
  scan.angle_min = -0.5 * fov;
  scan.angle_increment = fov / beams;
  scan.laser_pose = Pose2(0.2, 0.0, 0.0);
  const Pose2 sensor = robot * scan.laser_pose;
  for (int i = 0; i < beams; ++i) {
    const RayHit hit = world.castRay(sensor.translation(), sensor.theta + scan.bearing(static_cast<size_t>(i)),
                                     scan.range_max, Sensor::Laser);
    scan.ranges.push_back(hit.hit ? static_cast<float>(hit.range) : std::numeric_limits<float>::infinity());
  }
  return scan;
}

/// Distance from p to the nearest wall segment.
inline double distanceToWalls(const World& world, const Vec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const WallSegment& s : world.segments()) {
    const Vec2 e = s.b - s.a;
    const double t = std::clamp((p - s.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (s.a + t * e - p).norm());
  }
  return best;
}

/// Poses that see every wall of twoRoomWorld().
inline std::vector<Pose2> twoRoomPoses() {
  return {{1.0, 1.0, 0.0}, {1.5, 3.0, 1.0}, {2.2, 2.0, 0.0}, {3.8, 2.0, 0.0}, {5.0, 1.0, 2.0}, {4.5, 3.2, -2.0}};
}

inline OccupancyGrid twoRoomGrid(double resolution = 0.05) {
  const World world = twoRoomWorld();
  std::vector<LaserScan> scans;
  const auto poses = twoRoomPoses();
  for (const Pose2& p : poses) scans.push_back(castScan(world, p));
  GridOptions o;
  o.resolution = resolution;
  return buildGrid(scans, poses, o);
}

}  // namespace polarslam::test
