#include "odometry/odometry_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr int kMaxSubsteps = 10000;

OdometryMotionResult failure(OdometryFault fault, std::string why) {
  OdometryMotionResult result;
  result.fault = fault;
  result.error = std::move(why);
  return result;
}

std::string formatNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

bool carriesWheelTravel(const OdometryReading& r) { return r.left_travel != 0.0 || r.right_travel != 0.0; }

OdometrySource resolveSource(OdometrySource wanted, const OdometryReading& from, const OdometryReading& to) {
  if (wanted != OdometrySource::Auto) return wanted;
  return carriesWheelTravel(from) || carriesWheelTravel(to) ? OdometrySource::WheelTravel : OdometrySource::Pose;
}

bool finiteReading(const OdometryReading& r, OdometrySource source) {
  if (source == OdometrySource::WheelTravel) return std::isfinite(r.left_travel) && std::isfinite(r.right_travel);
  return std::isfinite(r.pose.x) && std::isfinite(r.pose.y) && std::isfinite(r.pose.theta);
}

struct RawIncrement {
  double distance = 0.0;  ///< m, |Δs| for wheel travel, chord length for poses
  double dtheta = 0.0;    ///< rad
};

RawIncrement rawIncrement(const OdometryReading& from, const OdometryReading& to, OdometrySource source,
                          double wheelbase) {
  if (source == OdometrySource::WheelTravel) {
    const double ds_right = to.right_travel - from.right_travel, ds_left = to.left_travel - from.left_travel;
    return {std::abs(0.5 * (ds_right + ds_left)), (ds_right - ds_left) / wheelbase};
  }
  const Pose2 delta = between(from.pose, to.pose);
  return {std::hypot(delta.x, delta.y), delta.theta};  // hypot: no overflow for absurd poses
}

/// Number of equal sub-steps so that each stays within the sub-step length and angle.
int substepCount(double ds, double dtheta, const OdometryModelParams& params) {
  const double needed = std::max(std::abs(ds) / params.max_substep_length, std::abs(dtheta) / params.max_substep_angle);
  return std::clamp(static_cast<int>(std::ceil(needed)), 1, kMaxSubsteps);
}

/// Covariance, in the start frame, of a constant-curvature arc (Δs, Δθ) whose input covariance
/// `input_cov` (of Δs, Δθ) accrues evenly along it.
Mat3 arcCovariance(double ds, double dtheta, const Mat2& input_cov, int substeps) {
  const double n = substeps;
  const Mat2 step_cov = input_cov / n;
  Pose2 pose;
  Mat3 cov = Mat3::Zero();
  for (int i = 0; i < substeps; ++i) {
    const Mat3 F = unicycleStateJacobian(pose, ds / n, dtheta / n);
    const Mat32 G = unicycleInputJacobian(pose, ds / n, dtheta / n);
    cov = F * cov * F.transpose() + G * step_cov * G.transpose();
    pose = unicycleStep(pose, ds / n, dtheta / n);
  }
  return cov;
}

/// (Δs, Δθ) = M·(Δs_R, Δs_L).
Eigen::Matrix2d wheelToUnicycle(double wheelbase) {
  Eigen::Matrix2d M;
  M << 0.5, 0.5, 1.0 / wheelbase, -1.0 / wheelbase;
  return M;
}

OdometryMotion wheelMotion(const OdometryReading& from, const OdometryReading& to, const OdometryModelParams& params) {
  const double ds_right = to.right_travel - from.right_travel, ds_left = to.left_travel - from.left_travel;
  const double B = params.wheels.wheelbase;
  OdometryMotion m;
  m.source = OdometrySource::WheelTravel;
  m.ds = 0.5 * (ds_right + ds_left);
  m.dtheta = (ds_right - ds_left) / B;
  const int n = substepCount(m.ds, m.dtheta, params);
  for (int i = 0; i < n; ++i) m.delta = differentialDriveStep(m.delta, ds_right / n, ds_left / n, B);
  const Eigen::Matrix2d M = wheelToUnicycle(B);
  const Mat2 input_cov = M * wheelTravelCovariance(ds_right, ds_left, params.wheels) * M.transpose();
  m.cov = arcCovariance(m.ds, m.dtheta, input_cov, n);
  return m;
}

/// sin(x)/x, with its limit 1 at 0.
double sinc(double x) { return std::abs(x) < 1e-9 ? 1.0 : std::sin(x) / x; }

OdometryMotion poseMotion(const OdometryReading& from, const OdometryReading& to, const OdometryModelParams& params) {
  OdometryMotion m;
  m.source = OdometrySource::Pose;
  m.delta = between(from.pose, to.pose);
  m.dtheta = m.delta.theta;
  // The recorded poses are taken as the ends of one constant-curvature arc: its chord has length
  // Δs·sinc(Δθ/2) and points along Δθ/2 when driving forwards.
  const double half = 0.5 * m.dtheta;
  const double chord = m.delta.translation().norm();
  const double forward = m.delta.x * std::cos(half) + m.delta.y * std::sin(half);
  m.ds = (forward < 0.0 ? -chord : chord) / sinc(half);
  const PoseIncrementErrorParams& k = params.poses;
  Mat2 input_cov = Mat2::Zero();
  input_cov(0, 0) = k.k_distance * std::abs(m.ds) + k.min_distance_sigma * k.min_distance_sigma;
  input_cov(1, 1) = k.k_heading_per_rad * std::abs(m.dtheta) + k.k_heading_per_m * std::abs(m.ds) +
                    k.min_heading_sigma * k.min_heading_sigma;
  m.cov = arcCovariance(m.ds, m.dtheta, input_cov, substepCount(m.ds, m.dtheta, params));
  return m;
}

/// Wheel travel over seconds is no single arc, but the odometry poses integrate the real path:
/// their difference is the increment. Its uncertainty is the sum of the two models' (the wheels'
/// for the distance each one turned, the poses' for the chord): neither knows the path.
OdometryMotion motionOverAGap(const OdometryReading& from, const OdometryReading& to, const OdometryModelParams& params) {
  OdometryMotion m = poseMotion(from, to, params);
  m.cov += wheelMotion(from, to, params).cov;
  return m;
}

void requireNonNegative(double value, const char* name) {
  if (!(value >= 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string("odometry model: ") + name + " must be finite and >= 0");
}
void requirePositive(double value, const char* name) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw std::invalid_argument(std::string("odometry model: ") + name + " must be finite and > 0");
}

}  // namespace

void validate(const OdometryModelParams& p) {
  requirePositive(p.wheels.wheelbase, "wheelbase");
  requireNonNegative(p.wheels.k_right, "k_right");
  requireNonNegative(p.wheels.k_left, "k_left");
  requireNonNegative(p.poses.k_distance, "k_distance");
  requireNonNegative(p.poses.k_heading_per_rad, "k_heading_per_rad");
  requireNonNegative(p.poses.k_heading_per_m, "k_heading_per_m");
  requireNonNegative(p.poses.min_distance_sigma, "min_distance_sigma");
  requireNonNegative(p.poses.min_heading_sigma, "min_heading_sigma");
  requirePositive(p.max_translation, "max_translation");
  requirePositive(p.max_rotation, "max_rotation");
  requireNonNegative(p.max_speed, "max_speed");
  requireNonNegative(p.max_turn_rate, "max_turn_rate");
  requirePositive(p.max_arc_interval, "max_arc_interval");
  requirePositive(p.max_substep_length, "max_substep_length");
  requirePositive(p.max_substep_angle, "max_substep_angle");
}

Pose2 differentialDriveStep(const Pose2& pose, double ds_right, double ds_left, double wheelbase) {
  return unicycleStep(pose, 0.5 * (ds_right + ds_left), (ds_right - ds_left) / wheelbase);
}

MotionJacobians differentialDriveJacobians(const Pose2& pose, double ds_right, double ds_left, double wheelbase) {
  const double ds = 0.5 * (ds_right + ds_left), dtheta = (ds_right - ds_left) / wheelbase;
  const double mu = pose.theta + 0.5 * dtheta;
  const double c = std::cos(mu), s = std::sin(mu), k = ds / (2.0 * wheelbase);
  MotionJacobians J;
  J.F_x = unicycleStateJacobian(pose, ds, dtheta);
  J.F_u << 0.5 * c - k * s, 0.5 * c + k * s,
           0.5 * s + k * c, 0.5 * s - k * c,
           1.0 / wheelbase, -1.0 / wheelbase;
  return J;
}

Mat2 wheelTravelCovariance(double ds_right, double ds_left, const WheelErrorParams& params) {
  Mat2 cov = Mat2::Zero();
  cov(0, 0) = params.k_right * std::abs(ds_right);
  cov(1, 1) = params.k_left * std::abs(ds_left);
  return cov;
}

void propagateWheelStep(Pose2& pose, Mat3& covariance, double ds_right, double ds_left,
                        const WheelErrorParams& params) {
  const MotionJacobians J = differentialDriveJacobians(pose, ds_right, ds_left, params.wheelbase);
  covariance = J.F_x * covariance * J.F_x.transpose() +
               J.F_u * wheelTravelCovariance(ds_right, ds_left, params) * J.F_u.transpose();
  pose = differentialDriveStep(pose, ds_right, ds_left, params.wheelbase);
}

Pose2 unicycleStep(const Pose2& pose, double ds, double dtheta) {
  const double mu = pose.theta + 0.5 * dtheta;
  return {pose.x + ds * std::cos(mu), pose.y + ds * std::sin(mu), wrapAngle(pose.theta + dtheta)};
}

Mat3 unicycleStateJacobian(const Pose2& pose, double ds, double dtheta) {
  const double mu = pose.theta + 0.5 * dtheta;
  Mat3 F = Mat3::Identity();
  F(0, 2) = -ds * std::sin(mu);
  F(1, 2) = ds * std::cos(mu);
  return F;
}

Mat32 unicycleInputJacobian(const Pose2& pose, double ds, double dtheta) {
  const double mu = pose.theta + 0.5 * dtheta;
  const double c = std::cos(mu), s = std::sin(mu);
  Mat32 G;
  G << c, -0.5 * ds * s,
       s, 0.5 * ds * c,
       0.0, 1.0;
  return G;
}

OdometryMotionResult odometryMotion(const OdometryReading& from, const OdometryReading& to,
                                    const OdometryModelParams& params) {
  const OdometrySource source = resolveSource(params.source, from, to);
  if (!finiteReading(from, source) || !finiteReading(to, source))
    return failure(OdometryFault::NonFinite, "odometry reading with a non-finite value");
  if (to.utime < from.utime)
    return failure(OdometryFault::TimeWentBackwards,
                   "odometry time went backwards by " + formatNumber(1e-6 * static_cast<double>(from.utime - to.utime)) +
                       " s");
  // Size check before the arc integration, so that absurd input costs nothing.
  const RawIncrement raw = rawIncrement(from, to, source, params.wheels.wheelbase);
  if (!std::isfinite(raw.distance) || !std::isfinite(raw.dtheta))
    return failure(OdometryFault::NonFinite, "odometry increment is not finite");
  // A restart or a dropped stretch leaves readings seconds apart: the robot may have gone as far
  // as it can drive in that time.
  const double dt = 1e-6 * static_cast<double>(to.utime - from.utime);
  const double max_translation = std::max(params.max_translation, params.max_speed * dt);
  const double max_rotation = std::max(params.max_rotation, params.max_turn_rate * dt);
  if (raw.distance > max_translation)
    return failure(OdometryFault::TooLarge, "odometry jumped " + formatNumber(raw.distance) + " m in " +
                                                formatNumber(dt) + " s between two readings (limit " +
                                                formatNumber(max_translation) + " m)");
  if (std::abs(raw.dtheta) > max_rotation)
    return failure(OdometryFault::TooLarge, "odometry turned " + formatNumber(std::abs(raw.dtheta)) + " rad in " +
                                                formatNumber(dt) + " s between two readings (limit " +
                                                formatNumber(max_rotation) + " rad)");
  OdometryMotionResult result;
  if (source != OdometrySource::WheelTravel) result.motion = poseMotion(from, to, params);
  else if (dt <= params.max_arc_interval || !finitePose(from.pose) || !finitePose(to.pose))
    result.motion = wheelMotion(from, to, params);
  else result.motion = motionOverAGap(from, to, params);
  return result;
}

void applyMotion(Pose2& pose, Mat3& covariance, const OdometryMotion& motion) {
  const Mat3 Ja = composeJacobianA(pose, motion.delta);
  const Mat3 Jb = composeJacobianB(pose);
  covariance = Ja * covariance * Ja.transpose() + Jb * motion.cov * Jb.transpose();
  pose = pose * motion.delta;
}

OdometryIntegrator::OdometryIntegrator(OdometryModelParams params) : params_(params) { validate(params_); }

OdometryMotionResult OdometryIntegrator::add(const OdometryReading& reading) {
  if (!last_) {
    const OdometrySource source = resolveSource(params_.source, reading, reading);
    if (!finiteReading(reading, source) || !std::isfinite(reading.pose.x) || !std::isfinite(reading.pose.y) ||
        !std::isfinite(reading.pose.theta)) {
      ++rejected_;
      return failure(OdometryFault::NonFinite, "odometry reading with a non-finite value");
    }
    last_ = reading;
    pose_ = Pose2(reading.pose.x, reading.pose.y, wrapAngle(reading.pose.theta));
    covariance_.setZero();
    OdometryMotionResult first;
    first.motion = OdometryMotion{};
    first.motion->source = source;
    return first;
  }
  OdometryMotionResult result = odometryMotion(*last_, reading, params_);
  if (result.ok()) {
    applyMotion(pose_, covariance_, *result.motion);
    last_ = reading;
    return result;
  }
  ++rejected_;
  if (result.fault == OdometryFault::TooLarge) last_ = reading;
  return result;
}

}  // namespace polarslam
