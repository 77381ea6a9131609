#include "common/pose_trail.hpp"

#include <cmath>

namespace polarslam {

void PoseTrail::add(const PoseStamped& pose, const std::string& frame) {
  utime_ = pose.utime;
  if (frame != frame_) poses_.clear();  // a new frame: the old poses mean nothing there
  frame_ = frame;
  if (!poses_.empty()) {
    const Pose2& last = poses_.back();
    const bool moved = std::hypot(pose.pose.x - last.x, pose.pose.y - last.y) >= kMinStep ||
                       std::abs(wrapAngle(pose.pose.theta - last.theta)) >= kMinTurn;
    if (!moved) return;
  }
  if (poses_.size() >= capacity_) {
    // Keep every other pose of the older half: long runs lose detail far back, not the recent path.
    const size_t half = poses_.size() / 2;
    std::vector<Pose2> kept;
    kept.reserve(capacity_);
    for (size_t i = 0; i < half; i += 2) kept.push_back(poses_[i]);
    kept.insert(kept.end(), poses_.begin() + static_cast<long>(half), poses_.end());
    poses_ = std::move(kept);
  }
  poses_.push_back(pose.pose);
  changed_ = true;
}

bool PoseTrail::takeChanged() {
  const bool was = changed_;
  changed_ = false;
  return was;
}

std::vector<Pose2> headingsAlong(const std::vector<Vec2>& points) {
  std::vector<Pose2> poses;
  double heading = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (i + 1 < points.size() && (points[i + 1] - points[i]).norm() > 0.0)
      heading = std::atan2(points[i + 1].y() - points[i].y(), points[i + 1].x() - points[i].x());
    poses.emplace_back(points[i].x(), points[i].y(), heading);
  }
  return poses;
}

}  // namespace polarslam
