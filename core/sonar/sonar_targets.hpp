#pragma once
#include <cstdint>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

enum class SonarKind : int8_t { Plane = 0, Corner = 1, Edge = 2, Unknown = 3 };

/// One advanced-sonar target in the array frame.
struct SonarTarget {
  SonarKind kind = SonarKind::Unknown;
  double range = 0.0;    ///< m
  double bearing = 0.0;  ///< rad
  Mat2 cov = Mat2::Zero();  ///< of (range, bearing)
};

struct SonarScan {
  int64_t utime = 0;
  int64_t seq = 0;
  int sensor_id = 0;
  Pose2 sensor_pose;       ///< array pose in the robot base frame
  double range_max = 8.0;
  double field_of_view = 1.0;
  std::vector<SonarTarget> targets;
};

}  // namespace polarslam
