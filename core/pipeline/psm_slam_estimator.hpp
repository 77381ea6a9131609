#pragma once
// `polarslam run --pipeline psm-slam`: PsmSlam over a log (the class polarslam-psm-slam runs
// live), then at the end a global pose-graph optimisation and the occupancy grid of the reference
// scans at their optimised poses (map.ot, map.bt, map.pgm + map.yaml, map.png; the same
// GraphScanStore polarslam-grid uses live). Two trajectories, one pose per scan: online (as
// published on PSM_SLAM_POSE at scan time) and final (each scan's pose relative to its reference
// scan, as published on PSM_SLAM_ANCHORS, re-placed by the final graph).
//
// Configuration (`--config FILE`, e.g. config/psm-slam.yaml, which lists every key with its
// default): the keys of PsmSlamParams (psm_slam_params.hpp) plus a `grid:` section.
#include <nlohmann/json.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "grid/graph_scan_store.hpp"
#include "map/map_store.hpp"
#include "pipeline/estimator.hpp"
#include "slam/psm_slam.hpp"
#include "slam/sonar_planes.hpp"

namespace polarslam {

struct PsmSlamMapOptions {
  double resolution = 0.05;  ///< m
  double max_range = 15.0;   ///< m
  bool all_scans = false;    ///< false: only the reference scans (they cover the map by construction)
};

/// The grid options of a PSM SLAM map (offline and in polarslam-grid).
GridOptions gridOptions(const PsmSlamMapOptions& map);

/// Advanced-sonar planes filled into the laser scans (slam/sonar_planes.hpp), when sonar arrives,
/// in scans where the laser sees little (max_return_fraction). Simulated glass-partition loop,
/// seeds 5000–5099: 1 run above 1 m (17 without it); the office is unchanged (its laser sees
/// enough everywhere; filling every scan made it worse, mean ATE 0.070 -> 0.110 m).
struct PsmSlamSonarOptions {
  bool fill_planes = true;
  SonarPlaneFillOptions fill;
  double max_age = 0.3;  ///< s: older sonar scans are not used
};

struct PsmSlamEstimatorConfig {
  PsmSlamParams slam;
  PsmSlamMapOptions map;
  PsmSlamSonarOptions sonar;
};

/// Every key of the configuration, bound to `config`.
void describePsmSlamEstimatorConfig(ParameterTable& table, PsmSlamEstimatorConfig& config);
/// Reads a configuration file (an empty path gives the defaults). Throws std::runtime_error
/// "FILE:LINE: ..." for unknown keys, values out of range and syntax errors.
PsmSlamEstimatorConfig loadPsmSlamEstimatorConfig(const std::string& yaml_path);

class PsmSlamEstimator : public Estimator {
 public:
  explicit PsmSlamEstimator(PsmSlamEstimatorConfig config = {});

  std::string name() const override { return "psm-slam"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  void onSonar(const SonarScan& scan) override;
  /// Final trajectory after finish(), the online one before.
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : online_; }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return online_; }
  /// Optimises, writes the grid files, adds "psm_slam" and "grid" figures to the report, and
  /// saves the map when saveMapTo() named a folder.
  void finish(const std::string& out_dir, nlohmann::json& report) override;
  /// Continues `map` (before any message): its graph and reference scans are this run's start,
  /// in its frame, and stay in the grid and in a saved map (PsmSlam::continueMap).
  void continueMap(const StoredMap& map, const Pose2& start, const Mat3& start_cov,
                   const std::optional<PsmSlamFilterSeed>& seed = std::nullopt);
  /// Localises in `map` instead (before any message): the same, but the map's poses are held
  /// where it has them (PsmSlam::freezeMap) and this run's reference scans are temporary.
  void localizeIn(const StoredMap& map, const Pose2& start, const Mat3& start_cov);
  /// Where finish() saves the map (core/map/map_store.hpp); empty: nowhere.
  void saveMapTo(std::string dir) { save_map_dir_ = std::move(dir); }
  /// The map of everything so far (graph as it is now), with the effective parameters.
  StoredMap storedMap() const;
  /// Saves storedMap() with its grid to the saveMapTo() folder now (a live SAVE_MAP request).
  /// Throws MapFormatError.
  void saveMapNow() const;
  /// What the latest scan did.
  const PsmSlamScanResult& lastResult() const { return last_result_; }

  const PsmSlam& slam() const { return slam_; }
  /// One per scan: its pose relative to its reference scan.
  const std::vector<AnchoredPose>& anchors() const { return anchors_; }
  /// Seconds spent inside the SLAM calls (odometry and scans), without log reading or maps.
  double slamSeconds() const { return slam_seconds_; }

 private:
  void writeMap(const std::string& out_dir, nlohmann::json& report);
  void saveStoredMap(const OccupancyGrid* grid, nlohmann::json& report) const;
  void saveWithGrid(nlohmann::json& report) const;

  PsmSlamEstimatorConfig config_;
  PsmSlam slam_;
  std::vector<PoseStamped> online_, final_;
  std::vector<AnchoredPose> anchors_;  ///< one per scan
  bool finished_ = false;
  GraphRefinementSummary refinement_;
  GraphScanStore map_scans_;           ///< the scans the map is built from
  double slam_seconds_ = 0.0;
  std::string save_map_dir_;
  PsmSlamScanResult last_result_;
  /// Latest planes per sonar array, with the time and odometry pose of their scan.
  struct SonarPlanesSeen {
    int64_t utime = 0;
    Pose2 odometry;
    std::vector<SonarPlane> planes;    ///< all of the scan's planes
    std::vector<SonarPlane> repeated;  ///< those the previous scan of the array also had: used
  };
  std::map<int, SonarPlanesSeen> sonar_planes_;
  Pose2 odometry_pose_;  ///< latest odometry pose
  size_t sonar_filled_readings_ = 0;
};

/// Report figures of a run: counts, optimisation, graph size.
nlohmann::json psmSlamReportJson(const PsmSlam& slam, const PoseGraphOptimizationSummary& final_optimization);
/// The final refinement's counts (report section psm_slam.refinement).
nlohmann::json refinementJson(const GraphRefinementSummary& refinement);

}  // namespace polarslam
