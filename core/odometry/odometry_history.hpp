#pragma once
// Recent odometry readings, for looking up the robot's motion between two timestamps (e.g. a
// sonar cycle and a laser scan) and for cutting a reading stream at a feature's timestamp.
#include <cstdint>
#include <deque>
#include <optional>

#include "odometry/odometry_model.hpp"
#include "odometry/odometry_reading.hpp"

namespace polarslam {

/// The reading at time t between `a` and `b` (a.utime ≤ t ≤ b.utime): pose, wheel travel and
/// velocities linearly interpolated, the heading along the shorter arc.
OdometryReading interpolateOdometry(const OdometryReading& a, const OdometryReading& b, int64_t t);

/// Pose covariance of ⊖Δ given that of Δ.
Mat3 inverseCovariance(const Pose2& delta, const Mat3& cov);

/// Relative pose of the robot at time `to` seen from its pose at time `from`, with covariance.
struct RelativeMotion {
  Pose2 delta;
  Mat3 cov = Mat3::Zero();
};

class OdometryHistory {
 public:
  explicit OdometryHistory(double keep_seconds = 5.0, OdometryModelParams model = {});

  /// Appends a reading; rejects (returns false) non-finite ones and ones older than the last.
  bool add(const OdometryReading& reading);
  /// The reading at t, interpolated; nullopt outside the stored time span.
  std::optional<OdometryReading> at(int64_t t) const;
  /// Motion from time `from` to time `to` (either order) with the odometry model's covariance;
  /// nullopt when either time lies outside the stored span or the model rejects the motion.
  std::optional<RelativeMotion> motion(int64_t from, int64_t to) const;

  bool empty() const { return readings_.empty(); }
  const OdometryModelParams& model() const { return model_; }

 private:
  int64_t keep_us_;
  OdometryModelParams model_;
  std::deque<OdometryReading> readings_;
};

}  // namespace polarslam
