#pragma once
// The map-then-localise experiment (issue 15's check, scripts/bench-localize): PSM SLAM maps the
// part of a log before `split_utime` and its map is stored as --save-map would store it; the rest
// of the log is localised in that map with its odometry moved far away by a rigid transform (so
// the odometry says nothing about where the robot starts in the map). The joined trajectory, the
// mapped part then the localised part in one frame, is what relation metrics score across the
// split.
#include <cstdint>
#include <vector>

#include "io/carmen.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"

namespace polarslam {

struct MapThenLocalizeResult {
  std::vector<PoseStamped> mapped;     ///< final SLAM poses of the scans before the split
  std::vector<PoseStamped> localized;  ///< final localised poses after the split, map frame
  std::vector<PoseStamped> joined;     ///< both, in time order
  std::vector<PoseStamped> online;     ///< localised part as published at scan time
  std::vector<bool> tied_to_map;       ///< per online pose: localised (not odometry only)
  MapLocalizerStats stats;
  size_t reference_scans = 0;
  double localize_seconds = 0.0;       ///< inside the localiser (the map loaded, scans prepared)
  double localized_duration_s = 0.0;   ///< data time of the localised part
};

/// `odometry_moved_by`: the rigid transform applied to every odometry reading after the split.
/// `known_start`: localisation starts from the mapping's last pose instead of searching.
MapThenLocalizeResult mapThenLocalize(const std::vector<CarmenEvent>& events, int64_t split_utime,
                                      const Pose2& odometry_moved_by, const PsmSlamEstimatorConfig& config,
                                      bool known_start = false);

}  // namespace polarslam
