#include "pipeline/map_then_localize.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include "io/stopwatch.hpp"
#include "map/map_store.hpp"

namespace polarslam {

int64_t halfwayLaserTime(const std::vector<CarmenEvent>& events) {
  std::vector<int64_t> stamps;
  for (const CarmenEvent& e : events)
    if (e.isLaser()) stamps.push_back(e.utime());
  if (stamps.empty()) return 0;
  std::sort(stamps.begin(), stamps.end());
  return stamps[stamps.size() / 2];
}

void runOverLog(Estimator& estimator, const std::vector<CarmenEvent>& events, int64_t until_utime) {
  for (const CarmenEvent& e : events) {
    if (e.utime() >= until_utime) continue;
    if (e.isLaser()) estimator.onLaser(e.laser());
    else estimator.onOdometry(e.odometry());
  }
  nlohmann::json report;
  estimator.finish("", report);
}

MapThenLocalizeResult mapThenLocalize(const std::vector<CarmenEvent>& events, int64_t split_utime,
                                      const PsmSlamEstimatorConfig& config, const MapThenLocalizeOptions& options) {
  MapThenLocalizeResult result;
  PsmSlamEstimator mapping(config);
  runOverLog(mapping, events, split_utime);
  result.mapped = mapping.trajectory();
  if (!result.mapped.empty()) result.mapped_end = result.mapped.back().pose;
  StoredMap map = mapping.storedMap();
  result.reference_scans = map.scans.size();

  const auto start = std::chrono::steady_clock::now();
  std::optional<Pose2> known_start;
  Mat3 start_cov = Mat3::Zero();  // the mapping's own uncertainty where it ended
  if (options.known_start && !result.mapped.empty()) {
    known_start = result.mapped.back().pose;
    start_cov = mapping.onlineTrajectory().back().cov;
  }
  std::unique_ptr<Estimator> second;
  const MapLocalizationEstimator* localization = nullptr;
  const MapContinuationEstimator* continuation = nullptr;
  if (options.continue_mapping) {
    auto estimator = std::make_unique<MapContinuationEstimator>(std::move(map), config, known_start, start_cov);
    continuation = estimator.get();
    second = std::move(estimator);
  } else {
    auto estimator = std::make_unique<MapLocalizationEstimator>(std::move(map), config, known_start, start_cov);
    localization = estimator.get();
    second = std::move(estimator);
  }
  int64_t first = 0, last = 0;
  for (const CarmenEvent& e : events) {
    if (e.utime() < split_utime) continue;
    if (e.isLaser()) {
      second->onLaser(e.laser());
      first = first ? std::min(first, e.utime()) : e.utime();
      last = std::max(last, e.utime());
      continue;
    }
    OdometryReading moved = e.odometry();
    moved.pose = options.odometry_moved_by * moved.pose;
    second->onOdometry(moved);
  }
  second->finish("", result.report);
  result.localize_seconds = secondsSince(start);
  result.localized_duration_s = 1e-6 * static_cast<double>(last - first);
  result.localized = second->trajectory();
  result.online = second->onlineTrajectory();
  const nlohmann::json& search = result.report["localization"];
  if (localization) {
    result.tied_to_map = localization->localizedFlags();
    result.stats = localization->localizer().stats();
    result.first_fix_scan = result.stats.first_fix_scan;
  } else {
    // The continued graph has moved the first half's reference scans too (the second half's loop
    // closures): its scans follow them.
    if (continuation->mapping()) result.mapped = reanchor(mapping.anchors(), continuation->mappingEstimator().slam().graph());
    // Continuing: odometry only until the scan that placed the robot, mapping from then on.
    const bool started = search.value("mapping_started", false);
    const size_t before = search.value("scans_before_mapping", size_t{0});
    const size_t placed = !started ? result.online.size() : before > 0 ? before - 1 : 0;
    result.first_fix_scan = started ? static_cast<int64_t>(placed) : -1;
    result.tied_to_map.assign(result.online.size(), false);
    for (size_t k = placed; k < result.online.size(); ++k) result.tied_to_map[k] = true;
  }
  result.joined = result.mapped;
  result.joined.insert(result.joined.end(), result.localized.begin(), result.localized.end());
  std::stable_sort(result.joined.begin(), result.joined.end(),
                   [](const PoseStamped& a, const PoseStamped& b) { return a.utime < b.utime; });
  return result;
}

}  // namespace polarslam
