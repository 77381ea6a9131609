#pragma once
// path_t and grid_status_t ⇄ core structs (polarslam-grid publishes them; polarslam-sim follows
// PLANNED_PATH). Conversions from LCM validate counts and values and return an error string.
#include <string>
#include <vector>

#include "grid/pose_regeneration.hpp"
#include "polarslam/path_t.hpp"

namespace polarslam {

/// GRID_PATH: the regenerated pose of every stored scan.
polarslam::path_t toLcmPath(const std::vector<int64_t>& scan_utimes, const std::vector<RegeneratedPose>& poses,
                            int64_t utime, int64_t seq);
/// PLANNED_PATH: waypoints in the map frame; theta is the direction of travel.
polarslam::path_t toLcmPath(const std::vector<Vec2>& waypoints, int64_t goal_utime, bool goal_exact, int64_t utime,
                            int64_t seq);
/// PSM_SLAM_PATH: a run's final trajectory, one pose per scan (source FINAL).
polarslam::path_t toLcmPath(const std::vector<PoseStamped>& trajectory, int64_t utime, int64_t seq);
/// The path's positions, checked: equal array lengths, finite values, at most 1e6 poses.
std::string fromLcm(const polarslam::path_t& msg, std::vector<Vec2>& positions);
/// The path's stamped poses (no covariance), checked as above and for finite headings.
std::string fromLcm(const polarslam::path_t& msg, std::vector<PoseStamped>& poses);

}  // namespace polarslam
