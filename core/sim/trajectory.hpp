#pragma once
// The true motion of the simulated differential-drive robot: a sequence of control periods,
// each with constant linear and angular velocity (a constant-curvature arc), so the pose and
// the wheels' travel are exact at any instant — which the laser needs, since every beam is
// measured at its own time.
#include <cstdint>
#include <deque>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Pose after moving for `tau` seconds at constant (v, ω) from `start` (exact arc).
Pose2 integrateArc(const Pose2& start, double v, double omega, double tau);

struct WheelTravel {
  double left = 0.0, right = 0.0;  ///< m, cumulative signed distance rolled by each wheel
};

class Trajectory {
 public:
  /// `wheel_base`: true distance between the wheels, to turn (v, ω) into wheel speeds.
  Trajectory(const Pose2& start, double wheel_base);

  /// Appends a period of `duration_us` µs at constant (v, ω).
  void append(int64_t duration_us, double v, double omega);

  /// Times are seconds since the start of the trajectory; queries are clamped to
  /// [earliest kept, end].
  double endTime() const { return 1e-6 * static_cast<double>(end_us_); }
  Pose2 poseAt(double t) const;
  WheelTravel wheelTravelAt(double t) const;
  /// Commanded (v, ω) in force at time t.
  double speedAt(double t) const;
  double turnRateAt(double t) const;
  Pose2 endPose() const { return end_pose_; }

  /// Drops periods that end before t (bounded memory on long runs).
  void forgetBefore(double t);

 private:
  struct Period {
    int64_t start_us = 0, duration_us = 0;
    Pose2 pose;          ///< at the start of the period
    WheelTravel travel;  ///< at the start of the period
    double v = 0.0, omega = 0.0;
  };
  const Period* periodAt(double t, double& tau) const;

  double wheel_base_;
  std::deque<Period> periods_;
  int64_t end_us_ = 0;
  Pose2 end_pose_;
  WheelTravel end_travel_;
};

}  // namespace polarslam
