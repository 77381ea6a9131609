#include "sim/path_follower.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace polarslam {
namespace {

constexpr size_t kSegmentSearchWindow = 3;  // segments ahead considered when tracking progress

}  // namespace

PathFollower::PathFollower(const DriveConfig& robot) : robot_(robot) {}

void PathFollower::setPath(std::vector<Vec2> waypoints, bool loop) {
  waypoints_ = std::move(waypoints);
  loop_ = loop && waypoints_.size() >= 2;
  segment_ = 0;
  completed_ = 0;
  finished_ = waypoints_.empty();
}

size_t PathFollower::segmentCount() const {
  if (loop_) return std::numeric_limits<size_t>::max();
  return waypoints_.size() >= 2 ? waypoints_.size() - 1 : 0;
}

Vec2 PathFollower::waypoint(size_t i) const { return waypoints_[i % waypoints_.size()]; }

double PathFollower::segmentProgress(const Vec2& p, size_t seg) const {
  const Vec2 a = waypoint(seg), e = waypoint(seg + 1) - a;
  return std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
}

void PathFollower::advanceAlongPath(const Vec2& p) {
  if (segmentCount() == 0) return;
  const size_t last = segmentCount() - 1;
  size_t best = segment_;
  double best_distance = distanceToSegment(p, waypoint(segment_), waypoint(segment_ + 1));
  for (size_t j = segment_ + 1; j <= std::min(last, segment_ + kSegmentSearchWindow); ++j) {
    const double d = distanceToSegment(p, waypoint(j), waypoint(j + 1));
    if (d < best_distance) {
      best_distance = d;
      best = j;
    }
  }
  // Also move on once the robot has passed the end of its segment.
  while (best < last && segmentProgress(p, best) >= 1.0) ++best;
  completed_ += best - segment_;
  segment_ = best;
}

Vec2 PathFollower::lookaheadPoint(const Vec2& p, double& remaining_path) const {
  remaining_path = std::numeric_limits<double>::infinity();
  if (segmentCount() == 0) {
    remaining_path = (waypoints_[0] - p).norm();
    return waypoints_[0];
  }
  const Vec2 a = waypoint(segment_), b = waypoint(segment_ + 1);
  Vec2 cursor = a + segmentProgress(p, segment_) * (b - a);
  double to_go = robot_.follower.lookahead;
  Vec2 target = cursor;
  bool placed = false;
  double along = 0.0;  // path length from the projection to the goal (non-looping paths)
  for (size_t seg = segment_; seg < segmentCount(); ++seg) {
    const Vec2 end = waypoint(seg + 1);
    const double length = (end - cursor).norm();
    if (!placed && length >= to_go) {
      target = cursor + (end - cursor) * (to_go / length);
      placed = true;
      if (loop_) return target;
    }
    if (!placed) to_go -= length;
    along += length;
    cursor = end;
    if (loop_ && seg > segment_ + waypoints_.size()) break;  // look-ahead longer than the loop
  }
  if (!placed) target = cursor;  // the goal itself
  if (!loop_) remaining_path = along;
  return target;
}

VelocityCommand PathFollower::desiredCommand(const Pose2& pose) {
  if (finished_) return {};
  const Vec2 p = pose.translation();
  advanceAlongPath(p);
  double remaining = 0.0;
  target_ = lookaheadPoint(p, remaining);
  const bool on_last_segment = !loop_ && (segmentCount() == 0 || segment_ + 1 >= segmentCount());
  if (on_last_segment && (waypoints_.back() - p).norm() < robot_.follower.goal_tolerance) {
    finished_ = true;
    if (segmentCount() > 0) completed_ = segmentCount();
    return {};
  }
  const Vec2 t = pose.inverseTransform(target_);
  const double alpha = std::atan2(t.y(), t.x());
  const PathFollowerConfig& f = robot_.follower;
  if (std::abs(alpha) > f.turn_in_place_angle)
    return {0.0, std::clamp(f.heading_gain * alpha, -robot_.max_turn_rate, robot_.max_turn_rate)};
  const double curvature = 2.0 * std::sin(alpha) / std::max(t.norm(), 1e-6);  // pure pursuit
  double v = robot_.max_speed;
  if (std::abs(curvature) > 1e-9) {
    v = std::min(v, robot_.max_turn_rate / std::abs(curvature));
    v = std::min(v, std::sqrt(f.max_lateral_accel / std::abs(curvature)));
  }
  if (std::isfinite(remaining)) v = std::min(v, std::sqrt(robot_.max_accel * remaining));  // stop at the goal
  return {v, curvature * v};
}

VelocityCommand PathFollower::limitAcceleration(const VelocityCommand& desired, const VelocityCommand& current,
                                                double dt) const {
  VelocityCommand out;
  const double dv = robot_.max_accel * dt;
  out.v = std::clamp(desired.v, current.v - dv, current.v + dv);
  // Keep the desired curvature when the speed is limited.
  double omega = desired.omega;
  if (std::abs(desired.v) > 1e-9) omega *= out.v / desired.v;
  const double dw = robot_.max_angular_accel * dt;
  out.omega = std::clamp(std::clamp(omega, current.omega - dw, current.omega + dw), -robot_.max_turn_rate,
                         robot_.max_turn_rate);
  return out;
}

VelocityCommand PathFollower::update(const Pose2& pose, const VelocityCommand& current, double dt) {
  return limitAcceleration(desiredCommand(pose), current, dt);
}

}  // namespace polarslam
