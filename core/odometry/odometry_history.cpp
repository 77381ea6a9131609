#include "odometry/odometry_history.hpp"

#include <algorithm>
#include <cmath>

namespace polarslam {

OdometryReading interpolateOdometry(const OdometryReading& a, const OdometryReading& b, int64_t t) {
  if (b.utime <= a.utime) return t <= a.utime ? a : b;
  const double f = std::clamp(static_cast<double>(t - a.utime) / static_cast<double>(b.utime - a.utime), 0.0, 1.0);
  auto lerp = [f](double u, double v) { return u + f * (v - u); };
  OdometryReading r = a;
  r.utime = t;
  r.pose = {lerp(a.pose.x, b.pose.x), lerp(a.pose.y, b.pose.y),
            wrapAngle(a.pose.theta + f * wrapAngle(b.pose.theta - a.pose.theta))};
  r.cov = a.cov + f * (b.cov - a.cov);
  r.left_travel = lerp(a.left_travel, b.left_travel);
  r.right_travel = lerp(a.right_travel, b.right_travel);
  r.v = lerp(a.v, b.v);
  r.omega = lerp(a.omega, b.omega);
  return r;
}

Mat3 inverseCovariance(const Pose2& delta, const Mat3& cov) {
  const double c = std::cos(delta.theta), s = std::sin(delta.theta);
  Mat3 J;
  J << -c, -s, s * delta.x - c * delta.y,
       s, -c, c * delta.x + s * delta.y,
       0.0, 0.0, -1.0;
  return J * cov * J.transpose();
}

OdometryHistory::OdometryHistory(double keep_seconds, OdometryModelParams model)
    : keep_us_(static_cast<int64_t>(keep_seconds * 1e6)), model_(model) {
  validate(model_);
}

bool OdometryHistory::add(const OdometryReading& reading) {
  const Pose2& p = reading.pose;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.theta) || !std::isfinite(reading.left_travel) ||
      !std::isfinite(reading.right_travel))
    return false;
  if (!readings_.empty() && reading.utime < readings_.back().utime) return false;
  readings_.push_back(reading);
  while (readings_.size() > 2 && readings_.front().utime < reading.utime - keep_us_) readings_.pop_front();
  return true;
}

std::optional<OdometryReading> OdometryHistory::at(int64_t t) const {
  if (readings_.empty() || t < readings_.front().utime || t > readings_.back().utime) return std::nullopt;
  const auto after = std::lower_bound(readings_.begin(), readings_.end(), t,
                                      [](const OdometryReading& r, int64_t time) { return r.utime < time; });
  if (after->utime == t || after == readings_.begin()) return *after;
  return interpolateOdometry(*(after - 1), *after, t);
}

std::optional<RelativeMotion> OdometryHistory::motion(int64_t from, int64_t to) const {
  const auto a = at(std::min(from, to)), b = at(std::max(from, to));
  if (!a || !b) return std::nullopt;
  const OdometryMotionResult result = odometryMotion(*a, *b, model_);
  if (!result.ok()) return std::nullopt;
  if (from <= to) return RelativeMotion{result.motion->delta, result.motion->cov};
  return RelativeMotion{result.motion->delta.inverse(), inverseCovariance(result.motion->delta, result.motion->cov)};
}

}  // namespace polarslam
