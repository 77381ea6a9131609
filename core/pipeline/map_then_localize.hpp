#pragma once
// The map-then-localise experiment (issue 15's check, scripts/bench-localize): PSM SLAM maps the
// part of a log before `split_utime` and its map is stored as --save-map would store it; the rest
// of the log is localised in that map with its odometry moved far away by a rigid transform (so
// the odometry says nothing about where the robot starts in the map). The joined trajectory, the
// mapped part then the localised part in one frame, is what relation metrics score across the
// split.
#include <cstdint>
#include <limits>
#include <vector>

#include "io/carmen.hpp"
#include "pipeline/map_continuation_estimator.hpp"
#include "pipeline/map_localization_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"

namespace polarslam {

struct MapThenLocalizeResult {
  std::vector<PoseStamped> mapped;     ///< final SLAM poses of the scans before the split (continue:
                                       ///< re-placed by the continued graph)
  std::vector<PoseStamped> localized;  ///< final localised poses after the split, map frame
  std::vector<PoseStamped> joined;     ///< both, in time order
  Pose2 mapped_end;                    ///< the mapping's last pose as it stands in the saved map
  std::vector<PoseStamped> online;     ///< localised part as published at scan time
  std::vector<bool> tied_to_map;       ///< per online pose: localised (not odometry only)
  MapLocalizerStats stats;             ///< localize: the localiser's counts
  int64_t first_fix_scan = -1;         ///< scan index (0-based) into the second half of the first fix
  nlohmann::json report;               ///< the second half's report figures (localization, psm_slam)
  size_t reference_scans = 0;
  double localize_seconds = 0.0;       ///< inside the localiser (the map loaded, scans prepared)
  double localized_duration_s = 0.0;   ///< data time of the localised part
};

/// Far from any map a log makes (250 m, −120 m, 2 rad): odometry moved by it says nothing about
/// where the robot starts in the map.
inline const Pose2 kOdometryFarAway(250.0, -120.0, 2.0);

struct MapThenLocalizeOptions {
  Pose2 odometry_moved_by;        ///< rigid transform applied to every odometry reading after the split
  bool known_start = false;       ///< start from the mapping's last pose instead of searching
  bool continue_mapping = false;  ///< --mode continue (new reference scans join the map) instead of localize
};

/// Where issue 15's check splits a log: the time of its middle laser scan.
int64_t halfwayLaserTime(const std::vector<CarmenEvent>& events);

/// Feeds the odometry and laser scans of `events` before `until_utime` to `estimator` and
/// finishes it (no output files).
void runOverLog(Estimator& estimator, const std::vector<CarmenEvent>& events,
                int64_t until_utime = std::numeric_limits<int64_t>::max());

MapThenLocalizeResult mapThenLocalize(const std::vector<CarmenEvent>& events, int64_t split_utime,
                                      const PsmSlamEstimatorConfig& config, const MapThenLocalizeOptions& options);

}  // namespace polarslam
