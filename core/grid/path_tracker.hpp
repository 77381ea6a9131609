#pragma once
// Path tracking against the SLAM map (thesis §3.7.1, docs/algorithms.md §17.11): a planned path lives in the
// map frame, and the robot knows where it is in that frame only through its SLAM estimate. The
// tracker keeps the progress along the path from the estimated pose and hands a low-level
// follower (which drives in some other frame: odometry, or the simulator's world frame) the
// remaining waypoints re-expressed around the robot: each waypoint keeps the offset from the
// robot that SLAM sees. When the map (and the estimate) shifts, the path moves with it.
//
//   PathTracker tracker;
//   tracker.setPath(plan.waypoints);                         // map frame
//   sim.setPath(tracker.update(slam_pose, sim.truePose()));  // on every SLAM pose
#include <cstddef>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

struct PathTrackerOptions {
  double waypoint_tolerance = 0.25;  ///< m: an intermediate waypoint this near counts as passed
  double goal_tolerance = 0.10;      ///< m: the goal counts as reached this near
};

class PathTracker {
 public:
  explicit PathTracker(PathTrackerOptions options = {}) : options_(options) {}

  /// New path in the map frame (the first waypoint is normally the robot's position).
  void setPath(std::vector<Vec2> map_waypoints);
  void clear();

  /// Updates progress from the estimated map pose and returns the remaining path for a follower
  /// driving in a frame where the same robot is at `drive_pose`: the robot's position first,
  /// then the waypoints still ahead. Empty once the goal is reached or without a path.
  std::vector<Vec2> update(const Pose2& map_pose, const Pose2& drive_pose);

  bool active() const { return !path_.empty() && !reached_; }
  bool goalReached() const { return reached_; }
  const std::vector<Vec2>& path() const { return path_; }
  /// Index of the waypoint the robot heads for.
  size_t nextWaypoint() const { return next_; }

 private:
  void advance(const Vec2& position);

  PathTrackerOptions options_;
  std::vector<Vec2> path_;
  size_t next_ = 0;
  bool reached_ = false;
};

/// Re-expresses map-frame points around a robot: p ↦ drive_pose ⊕ (map_pose ⊖ p).
std::vector<Vec2> reexpressAroundRobot(const std::vector<Vec2>& map_points, const Pose2& map_pose,
                                       const Pose2& drive_pose);

}  // namespace polarslam
