#pragma once
// `polarslam run --pipeline psm-slam`: PsmSlam over a log, then at the end a global pose-graph
// optimisation, one pose per scan (trajectory.tum) and the occupancy grid of the reference scans
// at their optimised poses (map.ot, map.bt, map.pgm + map.yaml, map.png).
//
// Configuration (`--config FILE`): the keys of PsmSlamParams (psm_slam_params.hpp) plus
//   grid_resolution: 0.05     # m
//   grid_max_range: 15        # m: beams only clear space up to this
//   grid_scans: keyframes     # keyframes (the reference scans) | all
#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

#include "slam/estimator.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam {

struct PsmSlamMapOptions {
  double resolution = 0.05;  ///< m
  double max_range = 15.0;   ///< m
  bool all_scans = false;    ///< false: only the reference scans (they cover the map by construction)
};

struct PsmSlamEstimatorConfig {
  PsmSlamParams slam;
  PsmSlamMapOptions map;
};

/// Reads PsmSlamParams keys plus the grid_* keys above. Throws std::runtime_error naming the file.
PsmSlamEstimatorConfig loadPsmSlamEstimatorConfig(const std::string& yaml_path);

class PsmSlamEstimator : public Estimator {
 public:
  explicit PsmSlamEstimator(PsmSlamEstimatorConfig config = {});

  std::string name() const override { return "psm-slam"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return trajectory_; }
  /// Optimises, writes the grid files, adds "psm_slam" and "grid" figures to the report.
  void finish(const std::string& out_dir, nlohmann::json& report) override;

  const PsmSlam& slam() const { return slam_; }
  /// Seconds spent inside the SLAM calls (odometry and scans), without log reading or maps.
  double slamSeconds() const { return slam_seconds_; }

 private:
  void writeMap(const std::string& out_dir, nlohmann::json& report);

  PsmSlamEstimatorConfig config_;
  PsmSlam slam_;
  std::vector<PoseStamped> trajectory_;
  std::vector<LaserScan> map_scans_;  ///< the scans the map is built from
  std::vector<size_t> map_scan_index_; ///< index of each in the trajectory (one pose per scan)
  size_t scans_seen_ = 0;
  double slam_seconds_ = 0.0;
};

/// Report figures of a run: counts, optimisation, graph size.
nlohmann::json psmSlamReportJson(const PsmSlam& slam, const PoseGraphOptimizationSummary& final_optimization);

}  // namespace polarslam
