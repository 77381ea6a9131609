#pragma once
// The EKF feature SLAM pipeline behind `polarslam run --pipeline ekf --sensors laser|sonar|fused`:
// laser scans → LaserFeatureExtractor (with sonar break hints when fused) → FeatureFusion (sonar
// features, laser-aided selection, information-weighted fusion) → FeatureSlam (EKF), the same
// core classes the polarslam-features, polarslam-fusion and polarslam-ekf-slam processes run.
//
// Configuration: by default the estimator describes the default simulated robot
// (config/robots/default.yaml). `--config FILE` takes either a robot file (its laser error model,
// wheel base and wheel-error constants are used) or an estimator file:
//   robot: config/robots/default.yaml   # optional: a robot file, relative to this file
//   ekf: {gate_probability: 0.99, new_feature_probability: 0.9999, confirm_observations: 3,
//         tentative_timeout_s: 2, max_line_extent_gap: 2.5, observation_cov_scale: 1,
//         anchor_radius: 5, max_anchors: 24, latency_s: 0.3, ambiguity_nis_margin: 9.21}
//   fusion: {gate_probability: 0.99, max_sonar_offset_s: 0.06, sonar_wait_s: 0.15,
//            laser_aided_selection: true, sonar_break_hints: true}
#include <memory>
#include <string>
#include <vector>

#include "grid/anchored_scan_store.hpp"
#include "laser/laser_feature_extractor.hpp"
#include "sim/sim_config.hpp"
#include "slam/estimator.hpp"
#include "slam/feature_slam.hpp"
#include "sonar/feature_fusion.hpp"

namespace polarslam {

enum class SlamSensors { Laser, Sonar, Fused };
/// "laser" | "sonar" | "fused"; throws std::invalid_argument otherwise.
SlamSensors parseSlamSensors(const std::string& name);
const char* toString(SlamSensors sensors);

struct FeatureSlamConfig {
  SlamSensors sensors = SlamSensors::Fused;
  LaserFeatureConfig laser;
  FeatureFusionParams fusion;
  FeatureSlamParams slam;
  bool sonar_break_hints = true;
};

/// The estimator configuration that describes a robot: odometry model from its wheel base and
/// wheel-error constants, laser error model, laser noise for the sonar selection gates, sonar
/// accuracy floors.
FeatureSlamConfig configForRobot(const SimConfig& robot, SlamSensors sensors);

/// Reads a robot file or an estimator file (see above). Throws std::runtime_error "FILE:LINE: ...".
FeatureSlamConfig loadFeatureSlamConfig(const std::string& path, SlamSensors sensors);

/// Writes the map as JSON: {"utime", "robot": {x, y, theta, cov}, "features": [{id, kind,
/// params, cov, endpoints (lines), observations}], "counts": {...}}.
std::string featureMapJson(const FeatureMap& map, int indent = 2);

class FeatureSlamEstimator : public Estimator {
 public:
  explicit FeatureSlamEstimator(FeatureSlamConfig config);

  std::string name() const override { return "ekf"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  void onSonar(const SonarScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return trajectory_; }
  /// Writes map.json and the occupancy grid regenerated from the anchored scans
  /// (map.{ot,bt,pgm,yaml,png}, core/grid) into out_dir and adds map, filter, fusion and grid
  /// figures to the report.
  void finish(const std::string& out_dir, nlohmann::json& report) override;

  /// Processes whatever is still queued (finish() does this too).
  void flush();
  const FeatureSlam& slam() const { return slam_; }
  const FeatureFusion& fusion() const { return fusion_; }
  const std::vector<ScanAnchors>& anchors() const { return anchors_; }
  /// Laser scans paired with their anchors, for the occupancy grid (bounded, see core/grid).
  const AnchoredScanStore& gridScans() const { return grid_scans_; }
  const FeatureSlamConfig& config() const { return config_; }
  /// Ids of map features first matched again after `revisit_after_s` seconds away from them
  /// (a loop closure), in the order they happened.
  const std::vector<std::pair<int64_t, int64_t>>& revisits() const { return revisits_; }

 private:
  void drain();

  FeatureSlamConfig config_;
  LaserFeatureExtractor extractor_;
  FeatureFusion fusion_;
  FeatureSlam slam_;
  std::vector<PoseStamped> trajectory_;
  std::vector<ScanAnchors> anchors_;
  AnchoredScanStore grid_scans_;
  std::vector<std::pair<int64_t, int64_t>> revisits_;  ///< (utime, feature id)
  std::map<int64_t, int64_t> last_seen_;               ///< feature id → utime
  Vec2 twist_ = Vec2::Zero();  ///< latest odometry (v, ω)
  long laser_scans_ = 0, sonar_scans_ = 0, rejected_ = 0;
};

/// Seconds away from a feature after which seeing it again counts as a revisit.
inline constexpr double kRevisitAfterSeconds = 30.0;

}  // namespace polarslam
