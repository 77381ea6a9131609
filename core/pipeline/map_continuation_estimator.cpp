#include "pipeline/map_continuation_estimator.hpp"

namespace polarslam {

MapContinuationEstimator::MapContinuationEstimator(StoredMap map, PsmSlamEstimatorConfig config,
                                                   std::optional<Pose2> initial_pose, const Mat3& initial_cov,
                                                   const std::optional<PsmSlamFilterSeed>& seed)
    : map_(std::move(map)), mapping_(config) {
  if (initial_pose) {
    startMapping(*initial_pose, initial_cov, seed);
  } else {
    localizer_ = std::make_unique<MapLocalizer>(mapReferences(map_), config.slam);
  }
}

void MapContinuationEstimator::startMapping(const Pose2& pose, const Mat3& cov,
                                            const std::optional<PsmSlamFilterSeed>& seed) {
  if (localizer_) {
    search_report_ = localizationReportJson(*localizer_, 0.0);
    before_mapping_ = localizer_->trajectory();
    localizer_.reset();
  }
  mapping_.continueMap(map_, pose, cov, seed);
  map_ = StoredMap{};  // the mapping holds its graph and scans now
  // The integrator starts from the latest reading, so no motion since it is lost.
  if (last_odometry_) mapping_.onOdometry(*last_odometry_);
}

void MapContinuationEstimator::onOdometry(const OdometryReading& odometry) {
  last_odometry_ = odometry;
  if (localizer_) localizer_->addOdometry(odometry);
  else mapping_.onOdometry(odometry);
}

void MapContinuationEstimator::onLaser(const LaserScan& scan) {
  if (!localizer_) {
    mapping_.onLaser(scan);
    online_.push_back(mapping_.onlineTrajectory().back());
    return;
  }
  const MapLocalizationResult r = localizer_->addScan(scan);
  online_.push_back(r.pose);
  ++scans_before_mapping_;
  if (r.localized) startMapping(r.pose.pose, r.pose.cov);
}

void MapContinuationEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  if (localizer_) {  // never placed in the map: the search is all there is
    final_ = localizer_->trajectory();
    report["localization"] = localizationReportJson(*localizer_, 0.0);
    report["localization"]["mapping_started"] = false;
    report["localization"]["scans_before_mapping"] = scans_before_mapping_;
    if (!save_map_.empty())
      report["saved_map"] = {{"folder", save_map_}, {"written", false},
                             {"reason", "the robot was never placed in the map: nothing was added to it"}};
    finished_ = true;
    return;
  }
  mapping_.finish(out_dir, report);
  final_ = before_mapping_;  // up to the scan that found the start
  const std::vector<PoseStamped>& mapped = mapping_.trajectory();
  final_.insert(final_.end(), mapped.begin(), mapped.end());
  finished_ = true;
  nlohmann::json section = search_report_.is_object() ? search_report_ : nlohmann::json::object();
  section["mapping_started"] = true;
  section["scans_before_mapping"] = scans_before_mapping_;
  section["map_reference_scans"] = mapping_.slam().mapKeyframes();
  report["localization"] = section;
}

}  // namespace polarslam
