#pragma once
// `polarslam run --pipeline ekf --sensors laser|sonar|fused`: the three stages of
// pipeline/feature_pipeline.hpp (laser features with sonar break hints → fusion → EKF SLAM) in
// one process, fed as the live processes are fed.
//
// Two trajectories, one pose per laser scan:
//  - online: the EKF's posterior pose at each scan's time, as published live in SCAN_ANCHORS;
//  - final:  every scan's pose regenerated from its anchors in the final map (thesis §3.7.2),
//            which is what a live run's recorded SCAN_ANCHORS and last SLAM_MAP give as well.
#include <map>
#include <string>
#include <vector>

#include "grid/anchored_scan_store.hpp"
#include "pipeline/estimator.hpp"
#include "pipeline/feature_pipeline.hpp"
#include "slam/feature_slam.hpp"
#include "sonar/feature_fusion.hpp"

namespace polarslam {

/// Writes the map as JSON: {"utime", "robot": {x, y, theta, cov}, "features": [{id, kind,
/// params, cov, endpoints (lines), observations}], "counts": {...}}.
std::string featureMapJson(const FeatureMap& map, int indent = 2);

/// The final trajectory of an EKF run: each scan's pose regenerated from its anchors in `map`.
std::vector<PoseStamped> regeneratedTrajectory(const std::vector<ScanAnchors>& anchors, const FeatureMap& map);
/// The online trajectory: each scan's pose as the EKF had it at the scan's time.
std::vector<PoseStamped> anchorPoses(const std::vector<ScanAnchors>& anchors);

class FeatureSlamEstimator : public Estimator {
 public:
  explicit FeatureSlamEstimator(FeaturePipelineConfig config);

  std::string name() const override { return "ekf"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  void onSonar(const SonarScan& scan) override;
  /// Final trajectory after finish() (regenerated poses), the online one before.
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : online_; }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return online_; }
  /// Writes map.json and the occupancy grid regenerated from the anchored scans
  /// (map.{ot,bt,pgm,yaml,png}, core/grid) into out_dir and adds map, filter, fusion and grid
  /// figures to the report.
  void finish(const std::string& out_dir, nlohmann::json& report) override;

  /// Processes whatever is still queued (finish() does this too).
  void flush();
  /// The filter's poses at every processed odometry time stamp (for filter consistency, NEES).
  const std::vector<PoseStamped>& filterPoses() const { return filter_poses_; }
  const FeatureSlam& slam() const { return slam_; }
  const FeatureFusion& fusion() const { return fusion_; }
  const std::vector<ScanAnchors>& anchors() const { return anchors_; }
  const FeaturePipelineConfig& config() const { return config_; }
  /// Ids of map features first matched again after `revisit_after_s` seconds away from them
  /// (a loop closure), in the order they happened.
  const std::vector<std::pair<int64_t, int64_t>>& revisits() const { return revisits_; }

 private:
  void drain();

  FeaturePipelineConfig config_;
  LaserFeatureStage features_;
  FeatureFusion fusion_;
  FeatureSlam slam_;
  std::vector<PoseStamped> filter_poses_, online_, final_;
  bool finished_ = false;
  std::vector<ScanAnchors> anchors_;
  AnchoredScanStore grid_scans_;
  std::vector<std::pair<int64_t, int64_t>> revisits_;  ///< (utime, feature id)
  std::map<int64_t, int64_t> last_seen_;               ///< feature id → utime
  long laser_scans_ = 0, sonar_scans_ = 0, rejected_ = 0;
};

/// Seconds away from a feature after which seeing it again counts as a revisit.
inline constexpr double kRevisitAfterSeconds = 30.0;

}  // namespace polarslam
