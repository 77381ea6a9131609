#pragma once
// A small simulated robot run for the PSM SLAM tests: a corridor loop around a block, with
// clutter so that no stretch of corridor is featureless, laser scans ray-cast from the true
// poses (World::castRay), and odometry whose increments carry noise and a heading bias, so that
// dead reckoning drifts and only matching and loop closure keep the estimate near the truth.
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_model.hpp"
#include "odometry/odometry_reading.hpp"
#include "sim/world.hpp"

namespace polarslam::testing {

/// Corridor 2 m wide around an 8 m × 4 m block inside a 12 m × 8 m outer wall, with boxes and
/// alcoves along the way.
inline World makeLoopWorld() {
  World world;
  world.addPolyline({{-6, -4}, {6, -4}, {6, 4}, {-6, 4}}, {Material::Wall}, true, "outer");
  world.addPolyline({{-4, -2}, {4, -2}, {4, 2}, {-4, 2}}, {Material::Wall}, true, "block");
  world.addBox({-2.0, -3.7}, {0.6, 0.6}, 0.0, Material::Wall, "box1");
  world.addBox({2.5, -2.3}, {0.4, 0.6}, 0.3, Material::Wall, "box2");
  world.addBox({5.6, 0.5}, {0.8, 0.5}, 0.0, Material::Wall, "box3");
  world.addBox({1.0, 3.6}, {1.0, 0.8}, 0.0, Material::Wall, "box4");
  world.addBox({-3.0, 2.4}, {0.5, 0.5}, 0.6, Material::Wall, "box5");
  world.addBox({-5.6, -1.0}, {0.8, 1.2}, 0.0, Material::Wall, "box6");
  world.addBox({-5.0, 2.8}, {0.3, 0.3}, 0.0, Material::Wall, "box7");
  return world;
}

struct SyntheticRunOptions {
  double speed = 0.5;              ///< m/s along straight legs
  double turn_rate = 0.8;          ///< rad/s on the spot at corners
  double scan_rate = 5.0;          ///< Hz
  double range_sigma = 0.01;       ///< m
  double odometry_sigma_per_m = 0.02;     ///< σ of distance error per √m
  double odometry_heading_sigma = 0.01;   ///< rad per √(rad + m)
  double heading_bias_per_m = 0.01;       ///< rad of systematic heading drift per metre
  double range_max = 8.0;
  int beams = 181;
  int laps = 1;
  int stationary_scans_at_start = 0;      ///< robot standing still before it drives
  uint64_t seed = 7;
};

/// The pose-increment error model of the runs' odometry with the default options (σ = 0.02 m per
/// √m of distance, 0.01 rad per √(rad + m) of heading, a heading bias of 0.01 rad per metre).
inline PoseIncrementErrorParams syntheticOdometryModel() {
  PoseIncrementErrorParams p;
  p.k_distance = 4e-4;
  p.k_heading_per_rad = 1e-4;
  p.k_heading_per_m = 2e-4;  // covers the heading bias
  return p;
}

struct SyntheticRun {
  std::vector<LaserScan> scans;
  std::vector<OdometryReading> odometry;  ///< one per scan, same utime, read just before it
  std::vector<Pose2> truth;               ///< true robot pose of each scan, in the start frame
};

inline LaserScan castScan(const World& world, const Pose2& pose, const SyntheticRunOptions& o, std::mt19937_64& rng,
                          int64_t utime) {
  std::normal_distribution<double> noise(0.0, o.range_sigma);
  LaserScan scan;
  scan.utime = utime;
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / (o.beams - 1);
  scan.range_max = o.range_max;
  scan.ranges.resize(static_cast<size_t>(o.beams));
  for (int i = 0; i < o.beams; ++i) {
    const RayHit hit = world.castRay(pose.translation(), pose.theta + scan.bearing(static_cast<size_t>(i)), o.range_max, Sensor::Laser);
    scan.ranges[static_cast<size_t>(i)] = hit.hit ? static_cast<float>(hit.range + noise(rng)) : std::numeric_limits<float>::infinity();
  }
  return scan;
}

/// True poses sampled at the scan rate along the centre line of the corridor loop.
inline std::vector<Pose2> loopPath(const SyntheticRunOptions& o) {
  const std::vector<Vec2> corners{{-5, -3}, {5, -3}, {5, 3}, {-5, 3}};
  const double step = o.speed / o.scan_rate, turn_step = o.turn_rate / o.scan_rate;
  std::vector<Pose2> path;
  Pose2 pose(corners[0].x(), corners[0].y(), 0.0);
  for (int i = 0; i < o.stationary_scans_at_start; ++i) path.push_back(pose);
  for (int lap = 0; lap < o.laps; ++lap) {
    for (size_t c = 0; c < corners.size(); ++c) {
      const Vec2 target = corners[(c + 1) % corners.size()];
      const double heading = std::atan2(target.y() - pose.y, target.x() - pose.x);
      while (std::abs(wrapAngle(heading - pose.theta)) > 1e-9) {  // turn on the spot
        const double d = wrapAngle(heading - pose.theta);
        pose.theta = wrapAngle(pose.theta + std::clamp(d, -turn_step, turn_step));
        path.push_back(pose);
      }
      while ((target - pose.translation()).norm() > 1e-9) {
        const Vec2 delta = target - pose.translation();
        const double length = std::min(step, delta.norm());
        pose.x += length * std::cos(heading);
        pose.y += length * std::sin(heading);
        path.push_back(pose);
      }
    }
  }
  return path;
}

/// The odometry's reading of a true step `delta`: distance noise, heading noise and heading bias.
inline Pose2 noisyOdometryStep(const Pose2& delta, const SyntheticRunOptions& o, std::mt19937_64& rng,
                               std::normal_distribution<double>& unit) {
  const double distance = delta.translation().norm();
  Pose2 noisy = delta;
  if (distance > 0 || std::abs(delta.theta) > 0) {
    noisy.x += o.odometry_sigma_per_m * std::sqrt(distance) * unit(rng);
    noisy.theta += o.odometry_heading_sigma * std::sqrt(distance + std::abs(delta.theta)) * unit(rng) +
                   o.heading_bias_per_m * distance;
  }
  return noisy;
}

inline SyntheticRun simulateLoopRun(const World& world, const SyntheticRunOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const std::vector<Pose2> path = loopPath(o);
  SyntheticRun run;
  const Pose2 start_inverse = path.front().inverse();
  Pose2 odometry_pose;
  const int64_t t0 = 1'000'000'000'000'000;
  const int64_t period = static_cast<int64_t>(1e6 / o.scan_rate);
  for (size_t k = 0; k < path.size(); ++k) {
    if (k > 0) odometry_pose = odometry_pose * noisyOdometryStep(between(path[k - 1], path[k]), o, rng, unit);
    const int64_t utime = t0 + static_cast<int64_t>(k) * period;
    OdometryReading reading;
    reading.utime = utime;
    reading.seq = static_cast<int64_t>(k);
    reading.pose = odometry_pose;
    run.odometry.push_back(reading);
    LaserScan scan = castScan(world, path[k], o, rng, utime);
    scan.seq = static_cast<int64_t>(k);
    run.scans.push_back(scan);
    run.truth.push_back(start_inverse * path[k]);
  }
  return run;
}

}  // namespace polarslam::testing
