#pragma once
// Scans for the scan-matching tests and benchmark, ray-cast in sim::World geometry: the v0.3
// test room and corridor (docs/algorithms.md §15.1), the project's room.yaml and a cluttered office.
// Noise is drawn from our own Box–Muller over mt19937_64, so a seed gives the same scans with
// any standard library.
#include <Eigen/Dense>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "sim/world.hpp"

namespace polarslam::fixtures {

class Noise {
 public:
  explicit Noise(uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal() {
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * uniform());
  }
  double normal(double sigma) { return sigma * normal(); }

 private:
  std::mt19937_64 engine_;
};

struct ScanSpec {
  size_t beams = 181;
  double fov = std::numbers::pi;  ///< centred on the laser's x axis
  double range_max = 80.0;        ///< readings beyond are "no return"
  double noise_sigma = 0.0;       ///< m, Gaussian range noise
};

/// Ray-casts one scan of `world` from the laser pose (world frame).
inline LaserScan simulateScan(const World& world, const Pose2& laser_pose, const ScanSpec& spec,
                              Noise* noise = nullptr) {
  LaserScan scan;
  scan.angle_increment = spec.fov / static_cast<double>(spec.beams - 1);
  scan.angle_min = -spec.fov / 2.0;
  scan.range_max = spec.range_max;
  scan.ranges.resize(spec.beams);
  for (size_t i = 0; i < spec.beams; ++i) {
    const RayHit hit = world.castRay(laser_pose.translation(), laser_pose.theta + scan.bearing(i), spec.range_max,
                                     Sensor::Laser);
    double r = hit.hit ? hit.range : std::numeric_limits<double>::quiet_NaN();
    if (hit.hit && noise && spec.noise_sigma > 0.0) r += noise->normal(spec.noise_sigma);
    scan.ranges[i] = static_cast<float>(r);
  }
  return scan;
}

inline std::vector<Vec2> rectangle(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

/// The v0.3 unit-test room (§15.1) in the polarslam frame: the laser at the origin looks along
/// +x; the front/back walls are 2 m away, the side walls 1.5 m.
inline World psmTestRoom() {
  World w;
  w.addPolyline(rectangle(-2.0, -1.5, 2.0, 1.5), {Material::Wall}, true, "room");
  return w;
}

/// The v0.3 corridor (§15.1): side walls 2 m to either side, the ends at 1.5·PM_MAX_RANGE (15 m),
/// beyond the 10 m far-point limit.
inline World psmTestCorridor() {
  World w;
  w.addPolyline(rectangle(-15.0, -2.0, 15.0, 2.0), {Material::Wall}, true, "corridor");
  return w;
}

/// A 9 × 7 m office with furniture, pillars and a doorway: enough structure for the tests of
/// accuracy, basin and covariance, and like the rooms PSM was tested in.
inline World clutteredOffice() {
  World w;
  w.addPolyline({{-4.5, 0.6}, {-4.5, -3.5}, {4.5, -3.5}, {4.5, 3.5}, {-4.5, 3.5}, {-4.5, 1.5}},
                {Material::Wall}, false, "walls with a doorway");
  w.addBox({-3.6, -2.7}, {1.2, 0.8}, 0.0, Material::Wall, "desk");
  w.addBox({3.2, 2.6}, {1.6, 0.7}, 0.0, Material::Wall, "shelf");
  w.addBox({1.5, -1.0}, {0.4, 0.4}, 0.3, Material::Wall, "pillar");
  w.addBox({-1.8, 1.9}, {0.9, 0.6}, -0.5, Material::Wall, "cabinet");
  w.addBox({3.7, -2.9}, {0.5, 0.5}, 0.0, Material::Wall, "bin");
  w.addPolyline({{0.5, 3.5}, {0.5, 2.4}}, {Material::Wall}, false, "partition");
  return w;
}

/// A long corridor with a few door recesses: the side walls dominate (corridor detection).
inline World officeCorridor() {
  World w;
  w.addPolyline({{-20.0, 1.0}, {-6.0, 1.0}, {-6.0, 1.4}, {-5.0, 1.4}, {-5.0, 1.0}, {4.0, 1.0}, {4.0, 1.4}, {5.0, 1.4},
                 {5.0, 1.0}, {20.0, 1.0}},
                {Material::Wall}, false, "north wall");
  w.addPolyline({{-20.0, -1.0}, {1.0, -1.0}, {1.0, -1.4}, {2.0, -1.4}, {2.0, -1.0}, {20.0, -1.0}}, {Material::Wall},
                false, "south wall");
  return w;
}

/// Distance from p to the nearest wall (ray-cast in 72 directions).
inline double clearance(const World& world, const Vec2& p) {
  double nearest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 72; ++k)
    nearest = std::min(nearest, world.castRay(p, k * std::numbers::pi / 36.0, 100.0, Sensor::Laser).range);
  return nearest;
}

/// Uniform random pose inside [x0, x1] × [y0, y1] with any heading.
inline Pose2 randomPose(Noise& noise, double x0, double y0, double x1, double y1) {
  return {noise.uniform(x0, x1), noise.uniform(y0, y1), noise.uniform(-std::numbers::pi, std::numbers::pi)};
}

/// A random pose error with translation uniform over the disc of radius `max_translation` and
/// heading uniform in ±max_rotation.
inline Pose2 randomError(Noise& noise, double max_translation, double max_rotation) {
  const double r = max_translation * std::sqrt(noise.uniform());
  const double a = noise.uniform(-std::numbers::pi, std::numbers::pi);
  return {r * std::cos(a), r * std::sin(a), noise.uniform(-max_rotation, max_rotation)};
}

/// Translation and rotation error of an estimate against the truth.
struct PoseError {
  double translation = 0.0, rotation = 0.0;
};
inline PoseError poseError(const Pose2& estimate, const Pose2& truth) {
  return {std::hypot(estimate.x - truth.x, estimate.y - truth.y), std::abs(wrapAngle(estimate.theta - truth.theta))};
}

/// Squared Mahalanobis distance of the error (x, y, θ) under cov.
inline double nees(const Pose2& estimate, const Pose2& truth, const Mat3& cov) {
  const Vec3 e(estimate.x - truth.x, estimate.y - truth.y, wrapAngle(estimate.theta - truth.theta));
  return e.dot(cov.ldlt().solve(e));
}

}  // namespace polarslam::fixtures
