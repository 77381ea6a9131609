#pragma once
// `polarslam run --pipeline psm-slam --load-map M --mode continue`: mapping goes on from a stored
// map, in its frame. Until the robot is placed in the map (the --initial-pose, or the first fix
// of the global search, core/slam/map_localizer.hpp) its poses are odometry only, as in
// localisation; from then on PSM SLAM continues the map (PsmSlam::continueMap): the stored
// reference scans are loop-closure candidates, new reference scans and closures join the loaded
// graph, and the grid and a saved map (--save-map) hold the old and the new parts.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "map/map_store.hpp"
#include "pipeline/estimator.hpp"
#include "pipeline/map_localization_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"

namespace polarslam {

class MapContinuationEstimator : public Estimator {
 public:
  /// `initial_pose`: a known start in the map frame; without it the start is searched globally.
  /// `seed`: with an initial pose, a run resumed from its own snapshot (PsmSlam::continueMap).
  MapContinuationEstimator(StoredMap map, PsmSlamEstimatorConfig config, std::optional<Pose2> initial_pose,
                           const Mat3& initial_cov = Mat3::Zero(),
                           const std::optional<PsmSlamFilterSeed>& seed = std::nullopt);

  std::string name() const override { return "psm-continue"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : online_; }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return online_; }
  /// Optimises the continued graph, writes its grid and the saved map (saveMapTo), and adds the
  /// "psm_slam" and "localization" (the search for the start) figures.
  void finish(const std::string& out_dir, nlohmann::json& report) override;
  void saveMapTo(std::string dir) {
    save_map_ = dir;
    mapping_.saveMapTo(std::move(dir));
  }

  /// Whether the robot has been placed in the map and mapping goes on.
  bool mapping() const { return !localizer_; }
  const PsmSlamEstimator& mappingEstimator() const { return mapping_; }

 private:
  void startMapping(const Pose2& pose, const Mat3& cov, const std::optional<PsmSlamFilterSeed>& seed = std::nullopt);

  StoredMap map_;  ///< until mapping starts
  PsmSlamEstimator mapping_;
  std::unique_ptr<MapLocalizer> localizer_;  ///< until the start is found
  nlohmann::json search_report_;             ///< the localiser's figures when the start was found
  std::optional<OdometryReading> last_odometry_;
  size_t scans_before_mapping_ = 0;
  std::vector<PoseStamped> before_mapping_;  ///< final poses of the scans before the start was found
  std::vector<PoseStamped> online_, final_;
  bool finished_ = false;
  std::string save_map_;
};

}  // namespace polarslam
