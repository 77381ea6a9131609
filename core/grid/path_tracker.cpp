#include "grid/path_tracker.hpp"

#include <algorithm>

namespace polarslam {

void PathTracker::setPath(std::vector<Vec2> map_waypoints) {
  path_ = std::move(map_waypoints);
  next_ = path_.size() > 1 ? 1 : 0;
  reached_ = false;
}

void PathTracker::clear() {
  path_.clear();
  next_ = 0;
  reached_ = false;
}

void PathTracker::advance(const Vec2& p) {
  const size_t last = path_.size() - 1;
  while (next_ < last) {
    const Vec2& target = path_[next_];
    const bool near = (target - p).norm() < options_.waypoint_tolerance;
    // Passed: beyond the line through the waypoint perpendicular to the segment leading to it.
    const Vec2 along = next_ > 0 ? Vec2(target - path_[next_ - 1]) : Vec2::Zero();
    const bool passed = along.squaredNorm() > 0.0 && (p - target).dot(along) > 0.0;
    if (!near && !passed) break;
    ++next_;
  }
  if (next_ == last && (path_[last] - p).norm() < options_.goal_tolerance) reached_ = true;
}

std::vector<Vec2> PathTracker::update(const Pose2& map_pose, const Pose2& drive_pose) {
  if (path_.empty() || reached_) return {};
  advance(map_pose.translation());
  if (reached_) return {};
  std::vector<Vec2> remaining{map_pose.translation()};
  remaining.insert(remaining.end(), path_.begin() + static_cast<std::ptrdiff_t>(next_), path_.end());
  return reexpressAroundRobot(remaining, map_pose, drive_pose);
}

std::vector<Vec2> reexpressAroundRobot(const std::vector<Vec2>& map_points, const Pose2& map_pose,
                                       const Pose2& drive_pose) {
  std::vector<Vec2> out;
  out.reserve(map_points.size());
  for (const Vec2& p : map_points) out.push_back(drive_pose.transform(map_pose.inverseTransform(p)));
  return out;
}

}  // namespace polarslam
