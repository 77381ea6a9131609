// Laser odometry against keyframes (core/scanmatch/laser_odometry) on a simulated drive through
// the cluttered office, with drifting wheel odometry as the prior.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "scan_fixtures.hpp"
#include "scanmatch/laser_odometry.hpp"

namespace polarslam {
namespace {

struct Drive {
  std::vector<LaserScan> scans;
  std::vector<OdometryReading> odometry;
  std::vector<Pose2> truth;  ///< robot poses at the scans
};

/// A loop of radius 1.2 m around (−1.5, −0.5) at 0.3 m/s, scans and odometry at 5 Hz. Odometry
/// drifts: 3 % scale error on distance and 1°/m of heading error, plus noise.
Drive loopDrive(uint64_t seed, double seconds = 25.0, const Pose2& mount = {}) {
  const World office = fixtures::clutteredOffice();
  fixtures::Noise noise(seed);
  fixtures::ScanSpec spec;
  spec.noise_sigma = 0.01;
  Drive d;
  const double radius = 1.2, speed = 0.3, dt = 0.2;
  Pose2 odometry;
  Pose2 previous;
  for (int k = 0; k * dt <= seconds; ++k) {
    const double a = speed * k * dt / radius;
    const Pose2 truth(-1.5 + radius * std::sin(a), -0.5 - radius * std::cos(a), a);
    if (k > 0) {
      const Pose2 step = between(previous, truth);
      const double distance = std::hypot(step.x, step.y);
      const Pose2 measured(1.03 * step.x + noise.normal(0.002), 1.03 * step.y + noise.normal(0.002),
                           step.theta + deg2rad(1.0) * distance + noise.normal(deg2rad(0.1)));
      odometry = odometry * measured;
    }
    previous = truth;
    const int64_t utime = 1'000'000 + k * 200'000;
    OdometryReading r;
    r.utime = utime;
    r.seq = k;
    r.pose = odometry;
    d.odometry.push_back(r);
    LaserScan scan = fixtures::simulateScan(office, truth * mount, spec, &noise);
    scan.utime = utime;
    scan.seq = k;
    scan.laser_pose = mount;
    d.scans.push_back(scan);
    d.truth.push_back(truth);
  }
  return d;
}

/// Position error of the estimate against the truth, both re-expressed relative to their start.
double endError(const std::vector<Pose2>& estimate, const std::vector<Pose2>& truth) {
  const Pose2 e = between(estimate.front(), estimate.back());
  const Pose2 t = between(truth.front(), truth.back());
  return std::hypot(e.x - t.x, e.y - t.y);
}

TEST(LaserOdometry, FollowsTheLoopFarBetterThanWheelOdometry) {
  const Drive d = loopDrive(3);
  LaserOdometry lo;
  std::vector<Pose2> estimate, wheels;
  for (size_t k = 0; k < d.scans.size(); ++k) {
    lo.addOdometry(d.odometry[k]);
    estimate.push_back(lo.addScan(d.scans[k]).pose);
    wheels.push_back(d.odometry[k].pose);
  }
  const double laser_error = endError(estimate, d.truth), wheel_error = endError(wheels, d.truth);
  std::printf("[ laser odometry ] %zu scans, %lld keyframes, %lld failed: end error %.3f m (wheels %.3f m)\n",
              d.scans.size(), static_cast<long long>(lo.keyframes()), static_cast<long long>(lo.failedMatches()),
              laser_error, wheel_error);
  EXPECT_EQ(lo.failedMatches(), 0);
  EXPECT_LT(laser_error, 0.05);
  EXPECT_LT(laser_error, 0.25 * wheel_error);
  // the covariance grows along the way but stays finite
  const Mat3 cov = lo.trajectory().back().cov;
  EXPECT_GT(cov(0, 0), 0.0);
  EXPECT_TRUE(std::isfinite(cov(2, 2)));
}

TEST(LaserOdometry, MountOffsetIsHandled) {
  const Pose2 mount(0.3, 0.05, 0.0);
  const Drive d = loopDrive(4, 10.0, mount);
  LaserOdometry lo;
  std::vector<Pose2> estimate;
  for (size_t k = 0; k < d.scans.size(); ++k) {
    lo.addOdometry(d.odometry[k]);
    estimate.push_back(lo.addScan(d.scans[k]).pose);
  }
  std::vector<Pose2> truth(d.truth.begin(), d.truth.begin() + static_cast<long>(estimate.size()));
  EXPECT_LT(endError(estimate, truth), 0.03);
  EXPECT_NEAR(wrapAngle(between(estimate.front(), estimate.back()).theta - between(truth.front(), truth.back()).theta),
              0.0, deg2rad(0.5));
}

TEST(LaserOdometry, WithoutOdometryAConstantVelocityPriorStillTracks) {
  const Drive d = loopDrive(5, 10.0);
  LaserOdometry lo;
  std::vector<Pose2> estimate;
  for (const LaserScan& s : d.scans) estimate.push_back(lo.addScan(s).pose);
  std::vector<Pose2> truth(d.truth.begin(), d.truth.begin() + static_cast<long>(estimate.size()));
  EXPECT_LT(endError(estimate, truth), 0.05);
}

TEST(LaserOdometry, HoldsThePoseWhileStandingStill) {
  const World office = fixtures::clutteredOffice();
  fixtures::Noise noise(6);
  fixtures::ScanSpec spec;
  spec.noise_sigma = 0.01;
  LaserOdometry lo;
  int held = 0;
  Pose2 first;
  for (int k = 0; k < 30; ++k) {
    OdometryReading r;
    r.utime = 1'000'000 + k * 100'000;
    r.pose = {2.0, 1.0, 0.5};  // unchanged
    lo.addOdometry(r);
    LaserScan s = fixtures::simulateScan(office, {-1.0, 0.0, 0.2}, spec, &noise);
    s.utime = r.utime;
    const LaserOdometryUpdate u = lo.addScan(s);
    if (k == 0) first = u.pose;
    held += u.held;
    EXPECT_LT(std::hypot(u.pose.x - first.x, u.pose.y - first.y), 0.01);
  }
  EXPECT_GE(held, 25);
  EXPECT_EQ(lo.keyframes(), 1);
  const Pose2 last = lo.trajectory().back().pose;
  EXPECT_LT(std::hypot(last.x, last.y), 0.01);
}

TEST(LaserOdometry, RejectsInvalidScans) {
  LaserOdometry lo;
  LaserScan bad;
  EXPECT_THROW(lo.addScan(bad), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
