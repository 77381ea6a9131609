#pragma once
// Simulated wheel odometry: the true wheel travel, scaled by the (unknown to the robot) wheel
// radius errors, plus zero-mean white noise whose variance grows with the distance each wheel
// rolls (σ² = k·|Δs|, docs/algorithms.md §17.6). The pose is integrated with the wheel base the robot
// believes in, and its covariance propagated with the same per-wheel variance model.
#include <cstdint>

#include "odometry/odometry_model.hpp"
#include "odometry/odometry_reading.hpp"
#include "sim/random.hpp"
#include "robot/robot_description.hpp"
#include "sim/trajectory.hpp"

namespace polarslam {

class OdometrySimulator {
 public:
  OdometrySimulator(const OdometryConfig& odometry, const DriveConfig& robot, uint64_t seed);

  /// The reading at `utime` when the wheels have truly rolled `true_travel` since the start
  /// (cumulative) and `dt` seconds passed since the previous reading. The odometry frame is
  /// the robot's pose at the first reading.
  OdometryReading measure(int64_t utime, const WheelTravel& true_travel, double dt);


 private:
  OdometryConfig config_;
  WheelErrorParams model_;
  Rng rng_;
  WheelTravel last_true_;
  WheelTravel measured_;
  Pose2 pose_;
  Mat3 cov_ = Mat3::Zero();
  int64_t seq_ = 0;
};

}  // namespace polarslam
