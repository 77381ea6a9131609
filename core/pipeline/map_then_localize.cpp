#include "pipeline/map_then_localize.hpp"

#include <algorithm>
#include <chrono>

#include "io/stopwatch.hpp"
#include "map/map_store.hpp"

namespace polarslam {

MapThenLocalizeResult mapThenLocalize(const std::vector<CarmenEvent>& events, int64_t split_utime,
                                      const Pose2& odometry_moved_by, const PsmSlamEstimatorConfig& config,
                                      bool known_start) {
  MapThenLocalizeResult result;
  PsmSlamEstimator mapping(config);
  for (const CarmenEvent& e : events) {
    if (e.utime() >= split_utime) continue;
    if (e.isLaser()) mapping.onLaser(e.laser());
    else mapping.onOdometry(e.odometry());
  }
  nlohmann::json report;
  mapping.finish("", report);
  result.mapped = mapping.trajectory();
  const std::vector<MapReference> references = mapReferences(mapping.storedMap());
  result.reference_scans = references.size();

  const auto start = std::chrono::steady_clock::now();
  MapLocalizer localizer(references, config.slam);
  if (known_start && !result.mapped.empty()) localizer.setInitialPose(result.mapped.back().pose, result.mapped.back().cov);
  int64_t first = 0, last = 0;
  for (const CarmenEvent& e : events) {
    if (e.utime() < split_utime) continue;
    if (e.isLaser()) {
      localizer.addScan(e.laser());
      first = first ? std::min(first, e.utime()) : e.utime();
      last = std::max(last, e.utime());
      continue;
    }
    OdometryReading moved = e.odometry();
    moved.pose = odometry_moved_by * moved.pose;
    localizer.addOdometry(moved);
  }
  result.localize_seconds = secondsSince(start);
  result.localized_duration_s = 1e-6 * static_cast<double>(last - first);
  result.localized = localizer.trajectory();
  result.online = localizer.onlineTrajectory();
  result.tied_to_map = localizer.localizedFlags();
  result.stats = localizer.stats();
  result.joined = result.mapped;
  result.joined.insert(result.joined.end(), result.localized.begin(), result.localized.end());
  std::stable_sort(result.joined.begin(), result.joined.end(),
                   [](const PoseStamped& a, const PoseStamped& b) { return a.utime < b.utime; });
  return result;
}

}  // namespace polarslam
