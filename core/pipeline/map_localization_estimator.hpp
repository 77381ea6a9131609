#pragma once
// `polarslam run --pipeline psm-slam --load-map M --mode localize`: localisation in a stored map
// (core/slam/map_localizer.hpp), the map unchanged. Online trajectory: the poses at scan time
// (odometry only until the first fix); final trajectory: the odometry-only stretches re-placed
// from the fix that ended them. The map's grid is drawn again with the localised trajectory.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "map/map_store.hpp"
#include "pipeline/estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"

namespace polarslam {

/// The "localization" report figures of a localiser (`seconds` spent in it).
nlohmann::json localizationReportJson(const MapLocalizer& localizer, double seconds);

class MapLocalizationEstimator : public Estimator {
 public:
  /// `initial_pose`: a known start in the map frame; without it the start is searched globally.
  MapLocalizationEstimator(StoredMap map, PsmSlamEstimatorConfig config, std::optional<Pose2> initial_pose,
                           const Mat3& initial_cov = Mat3::Zero());

  std::string name() const override { return "psm-localize"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : localizer_.onlineTrajectory(); }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return localizer_.onlineTrajectory(); }
  /// Adds the "localization" figures and writes map.png with the trajectory into `out_dir`.
  void finish(const std::string& out_dir, nlohmann::json& report) override;

  const MapLocalizer& localizer() const { return localizer_; }
  const StoredMap& map() const { return map_; }
  /// What the latest scan gave.
  const MapLocalizationResult& lastResult() const { return last_result_; }
  double seconds() const { return seconds_; }

 private:
  StoredMap map_;
  PsmSlamEstimatorConfig config_;
  MapLocalizer localizer_;
  std::vector<PoseStamped> final_;
  bool finished_ = false;
  double seconds_ = 0.0;
  MapLocalizationResult last_result_;
};

}  // namespace polarslam
