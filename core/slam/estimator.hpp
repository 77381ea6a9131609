#pragma once
// An estimator consumes sensor data in log order and produces a robot trajectory (and maps).
// `polarslam run` feeds every estimator from an LCM log through this interface; the live LCM
// processes call the same core classes, so a log gives the same result either way.
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

class Estimator {
 public:
  virtual ~Estimator() = default;
  virtual std::string name() const = 0;
  virtual void onOdometry(const OdometryReading&) {}
  virtual void onLaser(const LaserScan&) {}
  virtual void onSonar(const SonarScan&) {}
  /// A pose estimated elsewhere, e.g. recorded from a live run (see RecordedEstimator).
  virtual void onPose(const PoseStamped&) {}
  /// Robot base pose estimates in the map frame (= the robot's starting frame), in time order.
  virtual const std::vector<PoseStamped>& trajectory() const = 0;
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

/// The poses another estimator published (a live run's SLAM_POSE recorded with lcm-logger), in
/// time order: evaluates a live run with the same figures and plots as an offline one. Poses
/// older than the last one are dropped and counted (a logger can record out of order).
class RecordedEstimator : public Estimator {
 public:
  std::string name() const override { return "recorded"; }
  void onPose(const PoseStamped& pose) override;
  const std::vector<PoseStamped>& trajectory() const override { return trajectory_; }
  void finish(const std::string& out_dir, nlohmann::json& report) override;

 private:
  std::vector<PoseStamped> trajectory_;
  long out_of_order_ = 0;
};

}  // namespace polarslam
