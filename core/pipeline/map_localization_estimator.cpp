#include "pipeline/map_localization_estimator.hpp"

#include <chrono>

#include "grid/grid_files.hpp"
#include "grid/graph_scan_store.hpp"
#include "io/stopwatch.hpp"

namespace polarslam {

MapLocalizationEstimator::MapLocalizationEstimator(StoredMap map, PsmSlamEstimatorConfig config,
                                                   std::optional<Pose2> initial_pose, const Mat3& initial_cov)
    : map_(std::move(map)), config_(std::move(config)), localizer_(mapReferences(map_), config_.slam) {
  if (initial_pose) localizer_.setInitialPose(*initial_pose, initial_cov);
}

void MapLocalizationEstimator::onOdometry(const OdometryReading& odometry) {
  const auto start = std::chrono::steady_clock::now();
  localizer_.addOdometry(odometry);
  seconds_ += secondsSince(start);
}

void MapLocalizationEstimator::onLaser(const LaserScan& scan) {
  const auto start = std::chrono::steady_clock::now();
  last_result_ = localizer_.addScan(scan);
  seconds_ += secondsSince(start);
}

nlohmann::json localizationReportJson(const MapLocalizer& localizer, double seconds) {
  const MapLocalizerStats& s = localizer.stats();
  return {{"reference_scans", localizer.referenceCount()},
          {"scans", s.scans},
          {"unusable_scans", s.unusable_scans},
          {"matched_scans", s.matched_scans},
          {"odometry_only_scans", s.odometry_only_scans},
          {"match_failures", s.match_failures},
          {"new_ground_scans", s.new_ground_scans},
          {"off_map_timeouts", s.off_map_timeouts},
          {"gate_rejections", s.gate_rejections},
          {"odometry_faults", s.odometry_faults},
          {"global_searches", s.global_searches},
          {"global_matches", s.global_matches},
          {"global_ambiguous", s.global_ambiguous},
          {"global_see_through", s.global_see_through},
          {"global_unsupported", s.global_unsupported},
          {"global_unconfirmed", s.global_unconfirmed},
          {"fixes", s.fixes},
          {"losses", s.losses},
          {"first_fix_scan", s.first_fix_scan},
          {"localized_at_end", localizer.localized()},
          {"seconds", seconds}};
}

void MapLocalizationEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  final_ = localizer_.trajectory();
  finished_ = true;
  report["localization"] = localizationReportJson(localizer_, seconds_);
  if (out_dir.empty() || map_.scans.empty()) return;
  GraphScanStore store;
  for (const MapReferenceScan& s : map_.scans) store.add(s.scan, s.anchor);
  const GraphGrid grid = buildGraphGrid(store, map_.graph, gridOptions(config_.map));
  GridPicture picture = graphGridPicture(grid, map_.graph, final_);
  picture.title = "psm-localize: the stored map and the localised trajectory";
  const GridFiles files = writeGridFiles(out_dir, grid.grid, grid.slice, picture);
  report["grid"] = {{"written", true}, {"scans", store.size()}, {"files", {files.ot, files.bt, files.pgm, files.yaml, files.png}}};
}

}  // namespace polarslam
