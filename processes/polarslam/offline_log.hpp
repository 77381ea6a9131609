#pragma once
// Reads an LCM log of sensor channels into core structs, counting what it must reject.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

struct SensorChannelNames {
  std::string laser = "LASER", sonar = "SONAR", odometry = "ODOMETRY", ground_truth = "GROUND_TRUTH";
  std::string estimated_pose;  ///< pose_t estimates to read as well (empty: none)
};

struct SensorLogVisitor {
  std::function<void(const LaserScan&)> laser;
  std::function<void(const SonarScan&)> sonar;
  std::function<void(const OdometryReading&)> odometry;
  std::function<void(const PoseStamped&)> ground_truth;
  std::function<void(const PoseStamped&)> estimated_pose;
};

struct SensorLogSummary {
  std::map<std::string, long> messages;  ///< per channel, accepted
  std::map<std::string, long> rejected;  ///< per reason
  int64_t first_utime = 0, last_utime = 0;
  double durationSeconds() const { return static_cast<double>(last_utime - first_utime) * 1e-6; }
};

/// Calls the visitor's functions in log order; other channels are ignored. Messages that do
/// not decode or validate are counted in the summary (first of each reason logged to stderr).
SensorLogSummary visitSensorLog(const std::string& path, const SensorChannelNames& channels,
                                const SensorLogVisitor& visitor, const std::string& progress_label = "");

}  // namespace polarslam
