#pragma once
// Pure-pursuit path tracking for the simulated differential-drive robot: steer towards the
// point one look-ahead distance further along the path, slow down on curves (lateral
// acceleration and turn-rate limits) and before the final waypoint, turn on the spot when the
// path lies far to the side or behind.
#include <cstddef>
#include <vector>

#include "geometry/pose2.hpp"
#include "robot/robot_description.hpp"

namespace polarslam {

struct VelocityCommand {
  double v = 0.0;      ///< m/s
  double omega = 0.0;  ///< rad/s
};

class PathFollower {
 public:
  explicit PathFollower(const DriveConfig& robot);

  /// Replaces the path. With `loop`, the path continues from the last waypoint to the first
  /// and never finishes. An empty path means: stand still (finished).
  void setPath(std::vector<Vec2> waypoints, bool loop);

  /// Command for the next control period of `dt` seconds, given the true pose and the
  /// command currently in force (acceleration limits apply to the change).
  VelocityCommand update(const Pose2& pose, const VelocityCommand& current, double dt);

  bool finished() const { return finished_; }
  /// The point the robot is currently steering towards.
  Vec2 target() const { return target_; }

 private:
  size_t segmentCount() const;
  Vec2 waypoint(size_t i) const;  ///< cyclic for loops
  double segmentProgress(const Vec2& p, size_t seg) const;  ///< 0..1 along segment seg
  void advanceAlongPath(const Vec2& position);
  Vec2 lookaheadPoint(const Vec2& position, double& remaining_path) const;
  VelocityCommand desiredCommand(const Pose2& pose);
  VelocityCommand limitAcceleration(const VelocityCommand& desired, const VelocityCommand& current, double dt) const;

  DriveConfig robot_;
  std::vector<Vec2> waypoints_;
  bool loop_ = false;
  size_t segment_ = 0;  ///< current segment (waypoint segment_ → segment_ + 1), unbounded for loops
  size_t completed_ = 0;
  bool finished_ = true;
  Vec2 target_ = Vec2::Zero();
};

}  // namespace polarslam
