#include "scanmatch/laser_odometry.hpp"

#include <time.h>

#include <cmath>
#include <stdexcept>

namespace polarslam {
namespace {

constexpr size_t kMaxBufferedOdometry = 1000;

bool smallMotion(const Pose2& motion, double translation, double rotation) {
  return std::hypot(motion.x, motion.y) < translation && std::abs(motion.theta) < rotation;
}

Pose2 interpolate(const Pose2& a, const Pose2& b, double f) {
  return {a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), wrapAngle(a.theta + f * wrapAngle(b.theta - a.theta))};
}

}  // namespace

double threadCpuMicros() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

LaserOdometry::LaserOdometry(LaserOdometryParams params, PsmParams psm)
    : params_(params), matcher_(std::move(psm)) {}

void LaserOdometry::addOdometry(const OdometryReading& odometry) {
  odometry_.push_back(odometry);
  if (odometry_.size() > kMaxBufferedOdometry) odometry_.pop_front();
}

std::optional<Pose2> LaserOdometry::odometryAt(int64_t utime) const {
  if (odometry_.empty()) return std::nullopt;
  const auto gap = static_cast<int64_t>(params_.max_odometry_gap * 1e6);
  // Newest first: scans are usually at or just after the latest odometry.
  for (size_t k = odometry_.size(); k-- > 0;) {
    const OdometryReading& a = odometry_[k];
    if (a.utime == utime) return a.pose;
    if (a.utime > utime) continue;
    if (k + 1 < odometry_.size()) {  // bracketed by a and the next reading
      const OdometryReading& b = odometry_[k + 1];
      if (b.utime > utime && b.utime - a.utime <= 2 * gap) {
        const double f = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
        return interpolate(a.pose, b.pose, f);
      }
    }
    return utime - a.utime <= gap ? std::optional<Pose2>(a.pose) : std::nullopt;
  }
  const OdometryReading& first = odometry_.front();
  return first.utime - utime <= gap ? std::optional<Pose2>(first.pose) : std::nullopt;
}

Pose2 LaserOdometry::priorMotion(int64_t utime, const std::optional<Pose2>& odometry_now, bool& from_odometry) const {
  (void)utime;
  from_odometry = keyframe_->odometry && odometry_now;
  if (from_odometry) return between(*keyframe_->odometry, *odometry_now);
  // No odometry: constant velocity from the previous two estimates.
  return between(keyframe_->pose, last_pose_ * last_motion_);
}

Mat3 LaserOdometry::fallbackCovariance(const Pose2& motion) const {
  const double sxy = params_.fallback_sigma_xy + params_.fallback_fraction * std::hypot(motion.x, motion.y);
  const double sth = params_.fallback_sigma_theta + params_.fallback_fraction * std::abs(motion.theta);
  return Vec3(sxy * sxy, sxy * sxy, sth * sth).asDiagonal();
}

void LaserOdometry::makeKeyframe(PreparedScan&& scan, const LaserScan& raw, const Pose2& pose, const Mat3& cov,
                                 const std::optional<Pose2>& odometry) {
  keyframe_ = Keyframe{std::move(scan), raw.laser_pose, pose, cov, raw.utime, odometry};
  ++keyframes_;
}

LaserOdometryUpdate LaserOdometry::addScan(const LaserScan& scan) {
  const double start = threadCpuMicros();
  PreparedScan prepared = prepareScan(scan, matcher_.params());
  const std::optional<Pose2> odometry_now = odometryAt(scan.utime);
  ++scans_;
  LaserOdometryUpdate u;
  u.utime = scan.utime;
  if (!keyframe_) {
    makeKeyframe(std::move(prepared), scan, Pose2{}, Mat3::Zero(), odometry_now);
    u.new_keyframe = true;
  } else {
    const Keyframe& kf = *keyframe_;
    const Pose2 prior = priorMotion(scan.utime, odometry_now, u.prior_from_odometry);
    const Pose2 guess = laserPoseInReferenceLaser(Pose2{}, prior, kf.mount, scan.laser_pose);
    u.match = matcher_.match(kf.scan, prepared, guess, params_.method);
    u.matched = true;
    u.ref_utime = kf.utime;
    Pose2 motion = prior;
    Mat3 motion_cov = fallbackCovariance(prior);
    if (u.match.ok()) {
      motion = robotMotionFromLaserMotion(u.match.pose, kf.mount, scan.laser_pose);
      motion_cov = robotMotionCovariance(u.match.pose, u.match.cov, kf.mount, scan.laser_pose);
    } else {
      ++failed_;
    }
    u.pose = kf.pose * motion;
    const Mat3 Ja = composeJacobianA(kf.pose, motion), Jb = composeJacobianB(kf.pose);
    u.cov = Ja * kf.cov * Ja.transpose() + Jb * motion_cov * Jb.transpose();
    // Hold the pose when odometry and the match agree that the robot stands still: the match
    // alone jitters by millimetres even between identical views.
    if (u.match.ok() && u.prior_from_odometry && last_odometry_ &&
        smallMotion(between(*last_odometry_, *odometry_now), params_.still_odometry_translation,
                    params_.still_odometry_rotation) &&
        smallMotion(between(last_pose_, u.pose), params_.still_match_translation, params_.still_match_rotation)) {
      u.pose = last_pose_;
      u.cov = last_cov_;
      u.held = true;
      ++held_;
    }
    const bool moved_far = !smallMotion(between(kf.pose, u.pose), params_.keyframe_distance, params_.keyframe_angle);
    const bool little_overlap =
        u.match.ok() && u.match.valid_points < params_.keyframe_min_overlap * kf.scan.valid_count;
    if (!u.held && (!u.match.ok() || moved_far || little_overlap)) {
      makeKeyframe(std::move(prepared), scan, u.pose, u.cov, odometry_now);
      u.new_keyframe = true;
    }
  }
  last_motion_ = scans_ > 1 ? between(last_pose_, u.pose) : Pose2{};
  last_pose_ = u.pose;
  last_cov_ = u.cov;
  last_odometry_ = odometry_now;
  last_utime_ = scan.utime;
  u.match_time_us = threadCpuMicros() - start;
  trajectory_.push_back({u.utime, u.pose, u.cov});
  return u;
}

}  // namespace polarslam
