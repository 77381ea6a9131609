#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "odometry/odometry_model.hpp"

namespace polarslam {
namespace {

constexpr double kWheelbase = 0.5;

WheelErrorParams wheelParams() {
  WheelErrorParams p;
  p.wheelbase = kWheelbase;
  p.k_right = 5e-5;  // unequal wheels, so that the cross terms are exercised
  p.k_left = 2.5e-5;
  return p;
}

Vec3 poseDifference(const Pose2& a, const Pose2& b) { return {a.x - b.x, a.y - b.y, wrapAngle(a.theta - b.theta)}; }

// ---------------------------------------------------------------- Jacobians

TEST(OdometryModel, JacobiansMatchNumericalDifferentiation) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), travel(-0.3, 0.3), position(-5.0, 5.0);
  const double h = 1e-6;
  for (int trial = 0; trial < 50; ++trial) {
    const Pose2 pose(position(rng), position(rng), angle(rng));
    const double ds_right = travel(rng), ds_left = travel(rng);
    const MotionJacobians J = differentialDriveJacobians(pose, ds_right, ds_left, kWheelbase);
    Mat3 numeric_x;
    for (int c = 0; c < 3; ++c) {
      Vec3 d = Vec3::Zero();
      d(c) = h;
      const Pose2 plus = differentialDriveStep(Pose2(pose.vec() + d), ds_right, ds_left, kWheelbase);
      const Pose2 minus = differentialDriveStep(Pose2(pose.vec() - d), ds_right, ds_left, kWheelbase);
      numeric_x.col(c) = poseDifference(plus, minus) / (2 * h);
    }
    Mat32 numeric_u;
    numeric_u.col(0) = poseDifference(differentialDriveStep(pose, ds_right + h, ds_left, kWheelbase),
                                      differentialDriveStep(pose, ds_right - h, ds_left, kWheelbase)) / (2 * h);
    numeric_u.col(1) = poseDifference(differentialDriveStep(pose, ds_right, ds_left + h, kWheelbase),
                                      differentialDriveStep(pose, ds_right, ds_left - h, kWheelbase)) / (2 * h);
    EXPECT_LT((J.F_x - numeric_x).cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
    EXPECT_LT((J.F_u - numeric_u).cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
    EXPECT_LT((unicycleStateJacobian(pose, 0.5 * (ds_right + ds_left), (ds_right - ds_left) / kWheelbase) - J.F_x)
                  .cwiseAbs().maxCoeff(), 1e-15);
  }
}

TEST(OdometryModel, UnicycleInputJacobianMatchesNumericalDifferentiation) {
  const Pose2 pose(1.0, -2.0, 2.5);
  const double ds = 0.4, dtheta = -0.3, h = 1e-6;
  Mat32 numeric;
  numeric.col(0) = poseDifference(unicycleStep(pose, ds + h, dtheta), unicycleStep(pose, ds - h, dtheta)) / (2 * h);
  numeric.col(1) = poseDifference(unicycleStep(pose, ds, dtheta + h), unicycleStep(pose, ds, dtheta - h)) / (2 * h);
  EXPECT_LT((unicycleInputJacobian(pose, ds, dtheta) - numeric).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(OdometryModel, EkfPredictionWithAMotionEqualsTheDirectWheelUpdate) {
  // applyMotion composes pose ⊕ delta; with one sub-step this must be exactly §17.6's update.
  OdometryModelParams params;
  params.wheels = wheelParams();
  params.max_substep_length = 10.0;
  params.max_substep_angle = 10.0;
  OdometryReading from, to;
  from.right_travel = 3.0;
  from.left_travel = 2.0;
  to.right_travel = 3.25;
  to.left_travel = 2.15;
  const OdometryMotionResult r = odometryMotion(from, to, params);
  ASSERT_TRUE(r.ok()) << r.error;
  Pose2 pose_a(1.0, 2.0, 2.9), pose_b = pose_a;
  Mat3 P_a;
  P_a << 0.01, 0.002, 0.001, 0.002, 0.02, -0.001, 0.001, -0.001, 0.003;
  Mat3 P_b = P_a;
  applyMotion(pose_a, P_a, *r.motion);
  propagateWheelStep(pose_b, P_b, 0.25, 0.15, params.wheels);
  EXPECT_LT(poseDifference(pose_a, pose_b).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((P_a - P_b).cwiseAbs().maxCoeff(), 1e-15);
}

// ---------------------------------------------------------------- Monte Carlo

struct WheelPath {
  const char* name;
  std::vector<std::pair<double, double>> steps;  // nominal (Δs_R, Δs_L)
};

// The linearised model misses the shortening −∫θ²/2 ds of a wobbly straight run; it grows
// relative to σ_x like k·L³/B⁴, so the straight run is kept where linearisation holds (~2 %).
WheelPath straight() {
  return {"straight 3 m", std::vector<std::pair<double, double>>(60, {0.05, 0.05})};
}
WheelPath arc() {  // quarter circle of radius 2 m
  const int n = 100;
  const double dtheta = std::numbers::pi / 2 / n, ds = 2.0 * dtheta;
  return {"arc r = 2 m", std::vector<std::pair<double, double>>(
                             n, {ds + 0.5 * kWheelbase * dtheta, ds - 0.5 * kWheelbase * dtheta})};
}
WheelPath turnOnTheSpot() {  // half a turn
  const int n = 100;
  const double wheel = 0.5 * kWheelbase * std::numbers::pi / n;
  return {"turn on the spot", std::vector<std::pair<double, double>>(n, {wheel, -wheel})};
}

/// Empirical covariance of the end pose when every step's wheel travel gets N(0, k|Δs|) noise.
Mat3 monteCarloCovariance(const WheelPath& path, const WheelErrorParams& params, int samples, uint64_t seed,
                          const Pose2& nominal_end) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Mat3 sum = Mat3::Zero();
  for (int s = 0; s < samples; ++s) {
    Pose2 pose;
    for (const auto& [right, left] : path.steps) {
      const double noisy_right = right + std::sqrt(params.k_right * std::abs(right)) * normal(rng);
      const double noisy_left = left + std::sqrt(params.k_left * std::abs(left)) * normal(rng);
      pose = differentialDriveStep(pose, noisy_right, noisy_left, params.wheelbase);
    }
    const Vec3 e = poseDifference(pose, nominal_end);
    sum += e * e.transpose();
  }
  return sum / samples;
}

/// max |L⁻¹·S·L⁻ᵀ − I| with P = L·Lᵀ: 0.1 means S agrees with P within about 10% in every direction.
double whitenedDeviation(const Mat3& S, const Mat3& P) {
  const Eigen::LLT<Mat3> llt(P);
  EXPECT_EQ(llt.info(), Eigen::Success);
  const Mat3 L = llt.matrixL();
  const Mat3 Linv = L.inverse();
  return (Linv * S * Linv.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff();
}

TEST(OdometryModel, PropagatedCovarianceAgreesWithMonteCarlo) {
  const WheelErrorParams params = wheelParams();
  uint64_t seed = 11;
  for (const WheelPath& path : {straight(), arc(), turnOnTheSpot()}) {
    Pose2 nominal;
    Mat3 P = Mat3::Zero();
    for (const auto& [right, left] : path.steps) propagateWheelStep(nominal, P, right, left, params);
    const Mat3 S = monteCarloCovariance(path, params, 20000, seed++, nominal);
    EXPECT_LT(whitenedDeviation(S, P), 0.1) << path.name << "\nMonte Carlo:\n" << S << "\npropagated:\n" << P;
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(S(i, i) / P(i, i), 1.0, 0.1) << path.name << " diagonal " << i;
  }
}

TEST(OdometryModel, OneIncrementOverAWholeArcAgreesWithMonteCarlo) {
  // Readings far apart: odometryMotion integrates the arc in sub-steps (KODO-style), so one
  // increment must carry the same covariance as the fine-grained process.
  OdometryModelParams params;
  params.wheels = wheelParams();
  params.max_translation = 10.0;
  params.max_rotation = 4.0;
  uint64_t seed = 21;
  for (const WheelPath& path : {straight(), arc(), turnOnTheSpot()}) {
    OdometryReading from, to;
    for (const auto& [right, left] : path.steps) {
      to.right_travel += right;
      to.left_travel += left;
    }
    const OdometryMotionResult r = odometryMotion(from, to, params);
    ASSERT_TRUE(r.ok()) << r.error;
    Pose2 nominal;
    for (const auto& [right, left] : path.steps) nominal = differentialDriveStep(nominal, right, left, kWheelbase);
    EXPECT_LT(poseDifference(r.motion->delta, nominal).cwiseAbs().maxCoeff(), 1e-3) << path.name;
    const Mat3 S = monteCarloCovariance(path, params.wheels, 20000, seed++, nominal);
    EXPECT_LT(whitenedDeviation(S, r.motion->cov), 0.1) << path.name << "\nMonte Carlo:\n"
                                                        << S << "\nincrement:\n" << r.motion->cov;
  }
}

TEST(OdometryModel, StraightIncrementMatchesTheContinuousClosedForm) {
  // Straight run of length L: heading variance c·s grows along the path, so
  // σ_θ² = cL, σ_y² = cL³/3, cov(y, θ) = cL²/2, σ_x² = (k_R + k_L)L/4,
  // cov(x, θ) = (k_R − k_L)L/(2B), cov(x, y) = (k_R − k_L)L²/(4B), with c = (k_R + k_L)/B².
  OdometryModelParams params;
  params.wheels = wheelParams();
  params.max_translation = 10.0;
  const double L = 4.0, kR = params.wheels.k_right, kL = params.wheels.k_left, B = kWheelbase;
  OdometryReading from, to;
  to.right_travel = to.left_travel = L;
  const OdometryMotionResult r = odometryMotion(from, to, params);
  ASSERT_TRUE(r.ok());
  const Mat3& Q = r.motion->cov;
  const double c = (kR + kL) / (B * B);
  EXPECT_NEAR(Q(2, 2) / (c * L), 1.0, 1e-9);
  EXPECT_NEAR(Q(1, 1) / (c * L * L * L / 3.0), 1.0, 1e-3);
  EXPECT_NEAR(Q(1, 2) / (c * L * L / 2.0), 1.0, 1e-3);
  EXPECT_NEAR(Q(0, 0) / ((kR + kL) * L / 4.0), 1.0, 1e-3);
  EXPECT_NEAR(Q(0, 2) / ((kR - kL) * L / (2.0 * B)), 1.0, 1e-3);
  EXPECT_NEAR(Q(0, 1) / ((kR - kL) * L * L / (4.0 * B)), 1.0, 1e-2);
  EXPECT_NEAR(r.motion->ds, L, 1e-12);
  EXPECT_NEAR(r.motion->delta.x, L, 1e-12);
}

// ---------------------------------------------------------------- poses only (CARMEN)

OdometryReading poseReading(int64_t utime, double x, double y, double theta) {
  OdometryReading r;
  r.utime = utime;
  r.pose = Pose2(x, y, theta);
  return r;
}

TEST(OdometryModel, PoseIncrementsRecoverArcLengthAndDirection) {
  const OdometryModelParams params;
  const double R = 2.0, turn = 0.5;
  const OdometryMotionResult arc = odometryMotion(
      poseReading(0, 1.0, 1.0, 0.0), poseReading(100000, 1.0 + R * std::sin(turn), 1.0 + R * (1 - std::cos(turn)), turn),
      params);
  ASSERT_TRUE(arc.ok()) << arc.error;
  EXPECT_EQ(arc.motion->source, OdometrySource::Pose);
  EXPECT_NEAR(arc.motion->ds, R * turn, 1e-12);
  EXPECT_NEAR(arc.motion->dtheta, turn, 1e-12);
  EXPECT_NEAR(arc.motion->delta.x, R * std::sin(turn), 1e-12);

  const OdometryMotionResult back =
      odometryMotion(poseReading(0, 0, 0, std::numbers::pi), poseReading(1, 1.0, 0, std::numbers::pi), params);
  ASSERT_TRUE(back.ok());
  EXPECT_NEAR(back.motion->ds, -1.0, 1e-12);
}

TEST(OdometryModel, PoseIncrementVarianceGrowsWithDistanceAndTurnAboveAFloor) {
  OdometryModelParams params;
  PoseIncrementErrorParams& k = params.poses;
  const OdometryMotionResult still = odometryMotion(poseReading(0, 1, 1, 1), poseReading(1, 1, 1, 1), params);
  ASSERT_TRUE(still.ok());
  EXPECT_NEAR(still.motion->cov(0, 0), k.min_distance_sigma * k.min_distance_sigma, 1e-18);
  EXPECT_NEAR(still.motion->cov(2, 2), k.min_heading_sigma * k.min_heading_sigma, 1e-18);
  EXPECT_NEAR(still.motion->cov(1, 1), 0.0, 1e-18);

  const double L = 1.5;
  const OdometryMotionResult straight = odometryMotion(poseReading(0, 0, 0, 0), poseReading(1, L, 0, 0), params);
  const double heading_var = k.k_heading_per_m * L + k.min_heading_sigma * k.min_heading_sigma;
  EXPECT_NEAR(straight.motion->cov(0, 0), k.k_distance * L + k.min_distance_sigma * k.min_distance_sigma, 1e-12);
  EXPECT_NEAR(straight.motion->cov(2, 2), heading_var, 1e-12);
  EXPECT_NEAR(straight.motion->cov(1, 1) / (L * L * heading_var / 3.0), 1.0, 1e-2);

  const OdometryMotionResult turn = odometryMotion(poseReading(0, 0, 0, 0), poseReading(1, 0, 0, 1.0), params);
  EXPECT_NEAR(turn.motion->cov(2, 2), k.k_heading_per_rad + k.min_heading_sigma * k.min_heading_sigma, 1e-12);
}

TEST(OdometryModel, AutoSourcePrefersWheelTravelWhenPresent) {
  const OdometryModelParams params;
  OdometryReading from = poseReading(0, 0, 0, 0), to = poseReading(1, 5.0, 0, 0);  // poses disagree on purpose
  to.right_travel = to.left_travel = 0.1;
  const OdometryMotionResult r = odometryMotion(from, to, params);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.motion->source, OdometrySource::WheelTravel);
  EXPECT_NEAR(r.motion->ds, 0.1, 1e-12);
}

// ---------------------------------------------------------------- integrator and bad input

TEST(OdometryIntegrator, FollowsPoseOnlyOdometryExactly) {
  OdometryIntegrator integrator;
  double previous_trace = -1.0;
  for (int i = 0; i <= 60; ++i) {
    const double a = 0.05 * i;
    const OdometryMotionResult r =
        integrator.add(poseReading(i * 100000, 3.0 * std::sin(a), 3.0 * (1 - std::cos(a)), wrapAngle(a + 0.2)));
    ASSERT_TRUE(r.ok()) << r.error;
    EXPECT_GT(integrator.covariance().trace(), previous_trace);
    previous_trace = integrator.covariance().trace();
  }
  EXPECT_NEAR(integrator.pose().x, 3.0 * std::sin(3.0), 1e-9);
  EXPECT_NEAR(integrator.pose().y, 3.0 * (1 - std::cos(3.0)), 1e-9);
  EXPECT_NEAR(wrapAngle(integrator.pose().theta - 3.2), 0.0, 1e-9);
}

TEST(OdometryIntegrator, FollowsWheelTravelAlongACircle) {
  OdometryModelParams params;
  params.wheels.wheelbase = kWheelbase;
  OdometryIntegrator integrator(params);
  const double R = 1.5, step = 0.02;  // rad of the circle per reading
  for (int i = 0; i <= 100; ++i) {
    OdometryReading r;
    r.utime = i * 50000;
    r.right_travel = i * step * (R + 0.5 * kWheelbase);
    r.left_travel = i * step * (R - 0.5 * kWheelbase);
    ASSERT_TRUE(integrator.add(r).ok());
  }
  const double a = 100 * step;
  EXPECT_NEAR(integrator.pose().x, R * std::sin(a), 1e-4);
  EXPECT_NEAR(integrator.pose().y, R * (1 - std::cos(a)), 1e-4);
  EXPECT_NEAR(integrator.pose().theta, a, 1e-12);
}

TEST(OdometryIntegrator, BadReadingsGiveErrorsNotCrashes) {
  OdometryIntegrator integrator;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(integrator.add(poseReading(0, nan, 0, 0)).fault, OdometryFault::NonFinite);
  EXPECT_FALSE(integrator.started());
  ASSERT_TRUE(integrator.add(poseReading(1000000, 0, 0, 0)).ok());

  const OdometryMotionResult backwards = integrator.add(poseReading(900000, 0.1, 0, 0));
  EXPECT_EQ(backwards.fault, OdometryFault::TimeWentBackwards);
  EXPECT_NE(backwards.error.find("backwards by 0.1 s"), std::string::npos) << backwards.error;
  EXPECT_EQ(integrator.add(poseReading(1100000, 0, inf, 0)).fault, OdometryFault::NonFinite);
  EXPECT_EQ(integrator.add(poseReading(1100000, 1e308, -1e308, 0)).fault, OdometryFault::TooLarge);

  const OdometryMotionResult jump = integrator.add(poseReading(1200000, 50.0, 0, 0));
  EXPECT_EQ(jump.fault, OdometryFault::TooLarge);
  EXPECT_NE(jump.error.find("limit 2 m"), std::string::npos) << jump.error;
  EXPECT_EQ(integrator.pose().x, 0.0);
  // After the jump the new reading is the baseline: the next small step is accepted.
  const OdometryMotionResult after = integrator.add(poseReading(1300000, 50.1, 0, 0));
  ASSERT_TRUE(after.ok()) << after.error;
  EXPECT_NEAR(integrator.pose().x, 0.1, 1e-12);
  EXPECT_EQ(integrator.rejected(), 5u);

  OdometryReading spin;  // wheel travel that turns more than max_rotation at once
  spin.right_travel = 1.0;
  spin.left_travel = -1.0;
  EXPECT_EQ(odometryMotion(OdometryReading{}, spin, OdometryModelParams{}).fault, OdometryFault::TooLarge);
  spin.right_travel = std::numeric_limits<double>::max();
  spin.left_travel = -std::numeric_limits<double>::max();
  EXPECT_EQ(odometryMotion(OdometryReading{}, spin, OdometryModelParams{}).fault, OdometryFault::NonFinite);
}

// A restart or a dropped stretch of messages: the readings on either side are seconds and metres
// apart. The robot may have driven that far, and its wheel travel is no single arc any more,
// but the odometry poses integrate the real path.
TEST(OdometryIntegrator, ReadingsSecondsApartGiveThePosesDifference) {
  OdometryModelParams params;
  params.wheels.wheelbase = kWheelbase;
  // Drives 2 m straight, a quarter circle of radius 1 m to the left, then 1.5 m straight, at
  // 0.6 m/s; readings every 20 ms carry both the wheel travel and the integrated pose.
  std::vector<OdometryReading> path(1);
  const auto drive = [&](double distance, double radius) {
    const double step = 0.012;
    for (double done = 0.0; done < distance - 1e-9; done += step) {
      OdometryReading r = path.back();
      const double dr = std::isinf(radius) ? step : step * (radius + 0.5 * kWheelbase) / radius;
      const double dl = std::isinf(radius) ? step : step * (radius - 0.5 * kWheelbase) / radius;
      r.utime += 20000;
      r.right_travel += dr;
      r.left_travel += dl;
      r.pose = differentialDriveStep(r.pose, dr, dl, kWheelbase);
      path.push_back(r);
    }
  };
  const double inf = std::numeric_limits<double>::infinity();
  drive(2.0, inf);
  drive(0.5 * std::numbers::pi, 1.0);
  drive(1.5, inf);
  OdometryIntegrator integrator(params);
  ASSERT_TRUE(integrator.add(path.front()).ok());
  const OdometryMotionResult gap = integrator.add(path.back());
  ASSERT_TRUE(gap.ok()) << gap.error;
  const Pose2 truth = between(path.front().pose, path.back().pose);
  EXPECT_LT(between(gap.motion->delta, truth).translation().norm(), 1e-9);
  EXPECT_NEAR(wrapAngle(gap.motion->delta.theta - truth.theta), 0.0, 1e-9);
  // One arc of the same wheel travel would end far from where the robot is.
  OdometryModelParams one_arc = params;
  one_arc.max_arc_interval = 1e9;
  const OdometryMotionResult arc = odometryMotion(path.front(), path.back(), one_arc);
  ASSERT_TRUE(arc.ok());
  EXPECT_GT(between(truth, arc.motion->delta).translation().norm(), 0.5);
  // Its uncertainty is at least that of the wheels over the distance driven.
  EXPECT_GT((gap.motion->cov.topLeftCorner<2, 2>().trace()), 1e-4);

  // The same distance within a tenth of a second is a glitch, as before.
  OdometryReading glitch = path.front();
  glitch.utime += 100000;
  glitch.pose = path.back().pose;
  glitch.right_travel = path.back().right_travel;
  glitch.left_travel = path.back().left_travel;
  const OdometryMotionResult fast = odometryMotion(path.front(), glitch, params);
  EXPECT_EQ(fast.fault, OdometryFault::TooLarge);
  EXPECT_NE(fast.error.find("in 0.1 s"), std::string::npos) << fast.error;
}

TEST(OdometryIntegrator, RejectsInvalidParameters) {
  OdometryModelParams params;
  params.wheels.wheelbase = 0.0;
  EXPECT_THROW(OdometryIntegrator{params}, std::invalid_argument);
  params = {};
  params.wheels.k_left = -1.0;
  EXPECT_THROW(validate(params), std::invalid_argument);
  params = {};
  params.poses.min_heading_sigma = std::nan("");
  EXPECT_THROW(validate(params), std::invalid_argument);
  EXPECT_NO_THROW(validate(OdometryModelParams{}));
}

}  // namespace
}  // namespace polarslam
