#pragma once
#include <cstdint>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Cumulative wheel odometry of a differential-drive robot in its odometry frame.
struct OdometryReading {
  int64_t utime = 0;
  int64_t seq = 0;
  Pose2 pose;                ///< theta wrapped
  Mat3 cov = Mat3::Zero();
  double left_travel = 0.0;  ///< m, cumulative signed distance of the left wheel
  double right_travel = 0.0;
  double v = 0.0, omega = 0.0;
};

}  // namespace polarslam
