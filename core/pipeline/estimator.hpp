#pragma once
// An estimator consumes sensor data in log order and produces a robot trajectory (and maps).
// `polarslam run` feeds every estimator from an LCM log through this interface; the live LCM
// processes call the same core classes, so a log gives the same result either way.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "scanmatch/laser_odometry.hpp"
#include "slam/feature_map.hpp"
#include "slam/pose_graph.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual std::string name() const = 0;
  virtual void onOdometry(const OdometryReading&) {}
  virtual void onLaser(const LaserScan&) {}
  virtual void onSonar(const SonarScan&) {}
  /// What a live run published, recorded (see RecordedEstimator): poses, EKF scan anchors and
  /// maps, PSM SLAM anchored poses and pose graphs.
  virtual void onPose(const PoseStamped&) {}
  virtual void onScanAnchors(const ScanAnchors&) {}
  virtual void onFeatureMap(const FeatureMap&) {}
  virtual void onAnchoredPose(const AnchoredPose&) {}
  virtual void onPoseGraph(const PoseGraph&) {}
  /// A live run's final trajectory, one pose per scan (PSM_SLAM_PATH).
  virtual void onFinalPath(const std::vector<PoseStamped>&) {}
  /// Robot base pose estimates in the map frame (= the robot's starting frame), in time order:
  /// the final estimate, after finish() (later information, loop closures, optimisation included).
  virtual const std::vector<PoseStamped>& trajectory() const = 0;
  /// The poses as the estimator had them when each scan came in (what a live process publishes
  /// at scan time). The same as trajectory() for estimators that never revise the past.
  virtual const std::vector<PoseStamped>& onlineTrajectory() const { return trajectory(); }
  /// Called once after the last message: write maps into `out_dir`, add figures to `report`.
  virtual void finish(const std::string& /*out_dir*/, nlohmann::json& /*report*/) {}
};

/// Dead reckoning: the odometry poses, re-expressed relative to the first one.
class OdometryEstimator : public Estimator {
 public:
  std::string name() const override { return "odometry"; }
  void onOdometry(const OdometryReading& odometry) override;
  const std::vector<PoseStamped>& trajectory() const override { return trajectory_; }

 private:
  bool started_ = false;
  Pose2 origin_inverse_;
  std::vector<PoseStamped> trajectory_;
};

/// Laser odometry by polar scan matching (`polarslam run --pipeline psm`): the LaserOdometry
/// class the live polarslam-psm process runs, with its default parameters.
class LaserOdometryEstimator : public Estimator {
 public:
  std::string name() const override { return "psm"; }
  void onOdometry(const OdometryReading& odometry) override { odometry_.addOdometry(odometry); }
  void onLaser(const LaserScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return odometry_.trajectory(); }
  void finish(const std::string& out_dir, nlohmann::json& report) override;

 private:
  LaserOdometry odometry_;
  long unusable_scans_ = 0;
};

/// A live run scored from its recording (lcm-logger): evaluates it with the same figures and
/// plots as an offline run. Online trajectory: the EKF's SCAN_ANCHORS poses or PSM SLAM's
/// PSM_SLAM_POSE, i.e. the poses published at scan time (falling back to any recorded pose_t
/// channel). Final trajectory: the EKF's scan anchors regenerated in its last SLAM_MAP, or PSM
/// SLAM's anchored poses re-placed by its last PSM_SLAM_GRAPH — the same computation as the
/// offline estimators' — or, localising (no graph goes out), the PSM_SLAM_PATH published on exit,
/// the offline estimator's own final trajectory. Messages older than the previous one of their
/// kind are dropped and counted (a logger can record out of order).
class RecordedEstimator : public Estimator {
 public:
  std::string name() const override { return "recorded"; }
  void onPose(const PoseStamped& pose) override;
  void onScanAnchors(const ScanAnchors& anchors) override;
  void onFeatureMap(const FeatureMap& map) override;
  void onAnchoredPose(const AnchoredPose& pose) override;
  void onPoseGraph(const PoseGraph& graph) override;
  void onFinalPath(const std::vector<PoseStamped>& path) override;
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : online_; }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return online_; }
  void finish(const std::string& out_dir, nlohmann::json& report) override;

 private:
  bool inOrder(int64_t& last, int64_t utime);

  std::vector<PoseStamped> published_, online_, final_;
  std::vector<ScanAnchors> scan_anchors_;
  std::vector<AnchoredPose> anchored_;
  std::optional<FeatureMap> map_;
  std::optional<PoseGraph> graph_;
  std::optional<std::vector<PoseStamped>> final_path_;
  int64_t last_pose_ = INT64_MIN, last_anchors_ = INT64_MIN, last_anchored_ = INT64_MIN;
  long out_of_order_ = 0, maps_ = 0, graphs_ = 0;
  bool finished_ = false;
};

}  // namespace polarslam
