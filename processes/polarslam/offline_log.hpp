#pragma once
// Reads an LCM log of sensor channels into core structs, counting what it must reject.
#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "io/stream_time_gate.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "slam/feature_map.hpp"
#include "slam/pose_graph.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

struct SensorChannelNames {
  std::string laser = "LASER", sonar = "SONAR", odometry = "ODOMETRY", ground_truth = "GROUND_TRUTH";
  std::string estimated_pose;  ///< pose_t estimates to read as well (empty: none)
  /// What a recorded live run published besides poses (empty: none): the EKF's scan_anchors_t
  /// and slam_map_t, PSM SLAM's anchored_pose_t and pose_graph_t.
  std::string scan_anchors, slam_map, anchored_poses, pose_graph;
  std::string final_path;  ///< path_t: a run's final trajectory published on exit (empty: none)
};

struct SensorLogVisitor {
  std::function<void(const LaserScan&)> laser;
  std::function<void(const SonarScan&)> sonar;
  std::function<void(const OdometryReading&)> odometry;
  std::function<void(const PoseStamped&)> ground_truth;
  std::function<void(const PoseStamped&)> estimated_pose;
  std::function<void(const ScanAnchors&)> scan_anchors;
  std::function<void(const FeatureMap&)> slam_map;
  std::function<void(const AnchoredPose&)> anchored_pose;
  std::function<void(const PoseGraph&)> pose_graph;
  std::function<void(const std::vector<PoseStamped>&)> final_path;
};

/// The last PROCESS_STATUS of one process in a recorded live run.
struct ProcessCounts {
  std::string state;
  int64_t handled = 0, rejected = 0, dropped = 0;
};

struct SensorLogSummary {
  std::map<std::string, long> messages;  ///< per channel, accepted
  std::map<std::string, long> rejected;  ///< per reason
  std::map<std::string, ProcessCounts> processes;  ///< PROCESS_STATUS by process name (live recordings)
  std::vector<std::string> log_warnings;  ///< a truncated or corrupt log, with byte offsets
  /// Earliest and latest stamp delivered: a log recorded backwards still spans a positive time.
  int64_t first_utime = 0, last_utime = 0;
  bool any_stamp = false;
  void noteStamp(int64_t utime) {
    first_utime = any_stamp ? std::min(first_utime, utime) : utime;
    last_utime = any_stamp ? std::max(last_utime, utime) : utime;
    any_stamp = true;
  }
  double durationSeconds() const { return static_cast<double>(last_utime - first_utime) * 1e-6; }
};

/// Calls the visitor's functions in log order; PROCESS_STATUS goes into the summary; other
/// channels are ignored. Messages that do not decode or validate, or whose stamp jumps away from
/// the other channels' (StreamTimeGate), are counted in the summary (first of each reason logged
/// to stderr), as the live processes count them.
SensorLogSummary visitSensorLog(const std::string& path, const SensorChannelNames& channels,
                                const SensorLogVisitor& visitor, const std::string& progress_label = "",
                                const StreamTimeGateConfig& time_gate = {});

}  // namespace polarslam
