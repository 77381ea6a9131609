// Simulated odometry: Monte Carlo error statistics against the propagated covariance
// (docs/algorithms.md §17.6), systematic errors, and consistency with the simulated robot's true motion.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "sim/odometry_simulator.hpp"
#include "sim_test_helpers.hpp"

namespace polarslam {
namespace {

/// True wheel travel of a drive at constant (v, ω), sampled at the odometry rate.
struct Drive {
  double v = 0.0, omega = 0.0, seconds = 0.0;
};

struct MonteCarloResult {
  Mat3 empirical = Mat3::Zero();  ///< covariance of (odometry pose − true pose) over runs
  Mat3 propagated = Mat3::Zero(); ///< mean of the covariances the odometry published
  Vec3 mean_error = Vec3::Zero();
};

MonteCarloResult monteCarlo(const Drive& drive, const OdometryConfig& oc, int runs) {
  DriveConfig robot;
  const double rate = oc.rate, dt = 1.0 / rate;
  const int steps = static_cast<int>(std::lround(drive.seconds * rate));
  Trajectory truth(Pose2(), robot.wheel_base);
  for (int k = 0; k < steps; ++k) truth.append(std::llround(dt * 1e6), drive.v, drive.omega);
  const Pose2 true_end = truth.endPose();
  std::vector<WheelTravel> travel;
  for (int k = 0; k <= steps; ++k) travel.push_back(truth.wheelTravelAt(k * dt));
  std::vector<Vec3> errors;
  MonteCarloResult result;
  for (int run = 0; run < runs; ++run) {
    OdometrySimulator odo(oc, robot, streamSeed(1234, static_cast<uint64_t>(run)));
    OdometryReading r = odo.measure(0, travel[0], 0.0);
    for (int k = 1; k <= steps; ++k) r = odo.measure(k, travel[static_cast<size_t>(k)], dt);
    errors.push_back({r.pose.x - true_end.x, r.pose.y - true_end.y, wrapAngle(r.pose.theta - true_end.theta)});
    result.propagated += r.cov / runs;  // each run linearises about its own noisy path
  }
  for (const Vec3& e : errors) result.mean_error += e / runs;
  for (const Vec3& e : errors) result.empirical += (e - result.mean_error) * (e - result.mean_error).transpose() / (runs - 1);
  return result;
}

void expectCovariancesAgree(const MonteCarloResult& r, double tolerance) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.empirical(i, i) / r.propagated(i, i), 1.0, tolerance)
        << "diagonal " << i << "\nempirical\n" << r.empirical << "\npropagated\n" << r.propagated;
  }
  // Correlations too, on the scale of the diagonal.
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      const double scale = std::sqrt(r.propagated(i, i) * r.propagated(j, j));
      EXPECT_NEAR(r.empirical(i, j) / scale, r.propagated(i, j) / scale, 0.1) << i << "," << j;
    }
}

// The propagation is linear, so the variances are kept in the range where a linearisation
// holds (σ_θ of about 1°), as with real calibrated odometry over a few metres. Readings at
// 10 Hz keep the test fast; the noise model (variance ∝ distance) does not depend on the rate.
constexpr int kRuns = 2000;

OdometryConfig monteCarloOdometry(double k_left, double k_right) {
  OdometryConfig oc;
  oc.rate = 10.0;
  oc.k_left = k_left;
  oc.k_right = k_right;
  return oc;
}

TEST(OdometrySim, StraightRunErrorCovarianceMatchesPropagation) {
  const MonteCarloResult r = monteCarlo({0.5, 0.0, 10.0}, monteCarloOdometry(1e-5, 1e-5), kRuns);  // 5 m
  expectCovariancesAgree(r, 0.12);
  // Closed forms of a straight run of length L: σ_θ² = (k_L + k_R)L/B², lateral σ_y² ≈ L²σ_θ²/3,
  // along-track σ_x² = (k_L + k_R)L/4.
  const double L = 5.0, var_theta = 2e-5 * L / 0.25;
  EXPECT_NEAR(r.propagated(2, 2) / var_theta, 1.0, 0.01);
  EXPECT_NEAR(r.propagated(1, 1) / (L * L * var_theta / 3.0), 1.0, 0.05);
  EXPECT_NEAR(r.propagated(0, 0) / (2e-5 * L / 4.0), 1.0, 0.05);  // + second-order heading terms
  // Unbiased across and in heading; along the track the wandering heading shortens the run by
  // E∫θ²/2 ds = σ_θ²L/4 (second order, which the linear propagation leaves out).
  auto standardError = [&](int i) { return std::sqrt(r.empirical(i, i) / kRuns); };
  EXPECT_NEAR(r.mean_error(0), -var_theta * L / 4.0, 4.5 * standardError(0));
  EXPECT_NEAR(r.mean_error(1), 0.0, 4.5 * standardError(1));
  EXPECT_NEAR(r.mean_error(2), 0.0, 4.5 * standardError(2));
}

TEST(OdometrySim, ArcErrorCovarianceMatchesPropagation) {
  const MonteCarloResult r = monteCarlo({0.4, 0.3, 10.0}, monteCarloOdometry(2e-5, 0.5e-5), kRuns);  // 4 m, 172° left arc
  expectCovariancesAgree(r, 0.12);
}

TEST(OdometrySim, TurnOnTheSpotErrorCovarianceMatchesPropagation) {
  const MonteCarloResult r = monteCarlo({0.0, 0.8, 4.0}, monteCarloOdometry(1e-4, 1e-4), kRuns);
  // Each wheel rolls s = ωtB/2; the heading variance is (k_L s + k_R s)/B².
  const double s = 0.8 * 4.0 * 0.25;
  EXPECT_NEAR(r.propagated(2, 2) / (2e-4 * s / 0.25), 1.0, 0.01);
  expectCovariancesAgree(r, 0.12);
}

TEST(OdometrySim, SystematicRadiusErrorBendsAStraightRun) {
  // Right wheel 1 % larger than nominal: it rolls further than the odometry thinks, so the
  // odometry believes the robot turned right: Δθ = (s/(1+e) − s)/B per wheel travel s.
  OdometryConfig oc;
  oc.k_left = oc.k_right = 0.0;
  oc.right_radius_error = 0.01;
  DriveConfig robot;
  OdometrySimulator odo(oc, robot, 1);
  const OdometryReading r0 = odo.measure(0, {0.0, 0.0}, 0.0);
  const OdometryReading r = odo.measure(1, {10.0, 10.0}, 1.0);
  EXPECT_NEAR(r.right_travel, 10.0 / 1.01, 1e-12);
  EXPECT_NEAR(r.left_travel, 10.0, 1e-12);
  EXPECT_NEAR(r.pose.theta, (10.0 / 1.01 - 10.0) / 0.5, 1e-12);
  EXPECT_EQ(r0.pose.x, 0.0);
}

TEST(OdometrySim, WheelBaseErrorScalesTurnedAngle) {
  OdometryConfig oc;
  oc.k_left = oc.k_right = 0.0;
  oc.wheel_base_error = 0.02;  // odometry thinks the wheels are 2 % further apart
  DriveConfig robot;
  OdometrySimulator odo(oc, robot, 1);
  odo.measure(0, {0.0, 0.0}, 0.0);
  const double s = 0.25 * M_PI / 2;  // a true 90° turn on the spot with B = 0.5
  const OdometryReading r = odo.measure(1, {-s, s}, 1.0);
  EXPECT_NEAR(r.pose.theta, (M_PI / 2) / 1.02, 1e-12);
}

TEST(OdometrySim, ExactOdometryFollowsTheSimulatedRobot) {
  // Without errors, odometry equals the true motion expressed in the start frame.
  RobotDescription cfg = test::exactConfig();
  cfg.laser.enabled = false;
  cfg.sonars.clear();
  Simulator sim(loadWorld(test::sourcePath("config/worlds/room.yaml")), cfg, 3);
  const test::RecordingSink sink = test::run(sim, 20.0);
  ASSERT_EQ(sink.odometry.size(), sink.truth.size());  // both at 50 Hz
  const Pose2 start = sink.truth.front().pose;
  double travelled = 0.0;
  for (size_t i = 0; i < sink.odometry.size(); ++i) {
    ASSERT_EQ(sink.odometry[i].utime, sink.truth[i].utime);
    const Pose2 expected = between(start, sink.truth[i].pose);
    const Pose2& odo = sink.odometry[i].pose;
    EXPECT_NEAR(odo.x, expected.x, 2e-3) << i;
    EXPECT_NEAR(odo.y, expected.y, 2e-3) << i;
    EXPECT_NEAR(wrapAngle(odo.theta - expected.theta), 0.0, 1e-9) << i;
    if (i > 0) travelled += (sink.truth[i].pose.translation() - sink.truth[i - 1].pose.translation()).norm();
  }
  EXPECT_GT(travelled, 5.0);
  EXPECT_NEAR(0.5 * (sink.odometry.back().left_travel + sink.odometry.back().right_travel), travelled, 0.01);
}

TEST(OdometrySim, PublishedCovarianceGrowsWithDistance) {
  RobotDescription cfg;
  cfg.laser.enabled = false;
  cfg.sonars.clear();
  Simulator sim(loadWorld(test::sourcePath("config/worlds/room.yaml")), cfg, 3);
  const test::RecordingSink sink = test::run(sim, 10.0);
  ASSERT_GT(sink.odometry.size(), 400u);
  EXPECT_EQ(sink.odometry.front().cov, Mat3::Zero());
  for (size_t i = 50; i < sink.odometry.size(); i += 50) {
    EXPECT_GE(sink.odometry[i].cov(2, 2), sink.odometry[i - 50].cov(2, 2));
    EXPECT_GT(sink.odometry[i].cov.determinant(), 0.0);
  }
}

}  // namespace
}  // namespace polarslam
