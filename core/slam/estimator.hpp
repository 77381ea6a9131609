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

}  // namespace polarslam
