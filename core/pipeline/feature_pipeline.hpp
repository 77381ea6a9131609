#pragma once
// The feature-based EKF SLAM pipeline: one definition for `polarslam run --pipeline ekf` and the
// live processes, built from the same configuration file.
//
//   stage             live process            reads                           writes
//   laser features    polarslam-features      LASER, SONAR (hints), ODOMETRY  LASER_FEATURES (laser frame)
//   fusion            polarslam-fusion        LASER_FEATURES, SONAR, LASER,   FEATURES (base frame)
//                                             ODOMETRY
//   EKF SLAM          polarslam-ekf-slam      FEATURES, ODOMETRY, LASER       SLAM_POSE, SLAM_MAP, SCAN_ANCHORS
//
// Offline, FeatureSlamEstimator runs the three stages in one process and hands each input to the
// stages that read it in the order the processes receive it live (LASER reaches the EKF and the
// fusion before the LASER_FEATURES made from it), so the same messages give the same outputs.
// Every stage is deterministic in its input order and buffers by stream time (the fusion waits
// `sonar_wait_s` for sonar, the EKF `latency_s` for features), which absorbs the latency of the
// hops between processes; the set made from a LASER scan the stage has already received is
// waited for however late (up to max_laser_lag_s / max_feature_lag_s for a stalled peer).
//
// Configuration file (`--config`, the same for every stage): either a robot file
// (config/robots/*.yaml: laser error model, wheel base and wheel-error constants, sonar noise) or
// an estimator file such as config/ekf.yaml:
//   robot: robots/default.yaml   # optional: a robot file, relative to this file
//   ekf: {...}                   # FeatureSlamParams (see config/ekf.yaml for every key)
//   fusion: {...}                # FeatureFusionParams and sonar_break_hints
//   laser_features: {...}        # LaserFeatureConfig, as in config/laser-features.yaml
#include <optional>
#include <string>
#include <vector>

#include "config/parameter_table.hpp"
#include "laser/laser_feature_extractor.hpp"
#include "robot/robot_description.hpp"
#include "slam/feature_slam.hpp"
#include "sonar/feature_fusion.hpp"
#include "sonar/sonar_break_hints.hpp"

namespace polarslam {

enum class SlamSensors { Laser, Sonar, Fused };
/// "laser" | "sonar" | "fused"; throws std::invalid_argument otherwise.
SlamSensors parseSlamSensors(const std::string& name);
const char* toString(SlamSensors sensors);

struct FeaturePipelineConfig {
  SlamSensors sensors = SlamSensors::Fused;
  LaserFeatureConfig laser;
  FeatureFusionParams fusion;
  FeatureSlamParams slam;
  bool sonar_break_hints = true;  ///< fused only: sonar corners and edges break laser segments
};

/// The configuration that describes a robot: odometry model from its wheel base and wheel-error
/// constants, laser error model, laser noise for the sonar selection gates, sonar accuracy floors.
FeaturePipelineConfig configForRobot(const RobotDescription& robot, SlamSensors sensors);

/// The sections of a pipeline file: `ekf:` and `fusion:` (config/ekf.yaml lists their keys) and
/// `laser_features:` (config/laser-features.yaml lists its keys).
struct FeaturePipelineTables {
  ParameterTable ekf, fusion, laser_features;
};
/// Binds every section's keys to `config`.
void describeFeaturePipeline(FeaturePipelineTables& tables, FeaturePipelineConfig& config);

/// Reads a robot file or an estimator file (see above); an empty path gives the default robot's
/// configuration. Throws std::runtime_error "FILE:LINE: ...".
FeaturePipelineConfig loadFeaturePipelineConfig(const std::string& path, SlamSensors sensors);

/// The laser feature stage (polarslam-features): polar lines and right-angle corners of each
/// scan in the laser frame, with the sonar break hints of the latest sonar cycles (fused
/// sensors) and the robot's speed for the motion-during-scan error term (thesis §2.3.9).
class LaserFeatureStage {
 public:
  explicit LaserFeatureStage(const FeaturePipelineConfig& config);

  /// Whether this stage reads SONAR (only for break hints).
  bool usesSonar() const { return use_hints_; }
  /// False for a reading the odometry history refuses (non-finite, out of order).
  bool addOdometry(const OdometryReading& reading);
  void addSonar(const SonarScan& scan);
  /// Features of one scan (frame "laser"); `break_hints` holds the hint bearings used.
  FeatureSet extract(const LaserScan& scan) const;

  const LaserFeatureExtractor& extractor() const { return extractor_; }

 private:
  LaserFeatureExtractor extractor_;
  SonarBreakHintSource hints_;
  bool use_hints_ = false;
  std::optional<OdometryReading> latest_odometry_;
};

/// Odometry further than this from a scan says nothing about the robot's speed during it.
inline constexpr int64_t kMaxSpeedAgeUs = 500000;

}  // namespace polarslam
