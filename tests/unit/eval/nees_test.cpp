#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "geometry/chi_squared.hpp"
#include "eval/nees.hpp"

namespace polarslam {
namespace {

Mat3 correlatedCovariance() {
  Mat3 P;
  P << 0.04, 0.01, 0.002,
       0.01, 0.09, -0.003,
       0.002, -0.003, 0.0025;
  return P;
}

/// NEES of estimates drawn from N(truth, sample_cov) and scored with `claimed_cov`.
std::vector<double> monteCarloNees(const Mat3& sample_cov, const Mat3& claimed_cov, int samples, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const Mat3 L = sample_cov.llt().matrixL();
  const Pose2 truth(3.0, -2.0, 3.1);  // near π so that wrapping is exercised
  std::vector<double> nees;
  for (int i = 0; i < samples; ++i) {
    const Vec3 e = L * Vec3(normal(rng), normal(rng), normal(rng));
    const Pose2 estimate(truth.x + e.x(), truth.y + e.y(), wrapAngle(truth.theta + e.z()));
    nees.push_back(poseNees(estimate, claimed_cov, truth));
  }
  return nees;
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

TEST(ChiSquared, QuantilesMatchTables) {
  // Abramowitz & Stegun table 26.8 / any statistics table.
  EXPECT_NEAR(chiSquaredQuantile(0.95, 1), 3.841459, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.95, 2), 5.991465, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.95, 3), 7.814728, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.99, 2), 9.210340, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.5, 1), 0.454936, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.01, 10), 2.558212, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.99, 10), 23.209251, 1e-5);
  EXPECT_NEAR(chiSquaredQuantile(0.025, 60), 40.481748, 1e-4);
  EXPECT_NEAR(chiSquaredQuantile(0.975, 60), 83.297671, 1e-4);
  EXPECT_NEAR(chiSquaredQuantile(0.025, 100), 74.221927, 1e-4);
  EXPECT_NEAR(chiSquaredQuantile(0.975, 100), 129.561197, 1e-4);
  EXPECT_NEAR(chiSquaredQuantile(0.975, 3000), 3153.7035, 1e-3);  // large dof; value from mpmath
}

TEST(ChiSquared, CdfMatchesClosedFormsAndInvertsTheQuantile) {
  for (double x : {0.01, 0.5, 2.0, 7.0, 30.0}) {
    EXPECT_NEAR(chiSquaredCdf(x, 2), 1.0 - std::exp(-0.5 * x), 1e-13) << x;
    EXPECT_NEAR(chiSquaredCdf(x, 1), std::erf(std::sqrt(0.5 * x)), 1e-13) << x;
  }
  for (double dof : {1.0, 3.0, 17.0, 240.0})
    for (double p : {0.001, 0.025, 0.5, 0.975, 0.999})
      EXPECT_NEAR(chiSquaredCdf(chiSquaredQuantile(p, dof), dof), p, 1e-12) << dof << " " << p;
  EXPECT_EQ(chiSquaredCdf(-1.0, 3), 0.0);
  EXPECT_THROW(chiSquaredQuantile(1.0, 3), std::invalid_argument);
  EXPECT_THROW(chiSquaredQuantile(0.5, 0), std::invalid_argument);
}

TEST(Nees, IntervalForTwentyRunsOfAPose) {
  const NeesInterval i = averageNeesInterval(3, 20);
  EXPECT_NEAR(i.lower, 40.481748 / 20.0, 1e-5);
  EXPECT_NEAR(i.upper, 83.297671 / 20.0, 1e-5);
}

TEST(Nees, CorrectGaussianAveragesToTheDimension) {
  const Mat3 P = correlatedCovariance();
  const std::vector<double> nees = monteCarloNees(P, P, 20000, 42);
  // Mean of 20000 χ²(3) values: standard error √(6/20000) ≈ 0.017.
  EXPECT_NEAR(mean(nees), 3.0, 0.07);
  const NeesInterval interval = averageNeesInterval(3, 20000);
  EXPECT_GT(mean(nees), interval.lower);
  EXPECT_LT(mean(nees), interval.upper);
}

TEST(Nees, OverAndUnderConfidenceShowUp) {
  const Mat3 P = correlatedCovariance();
  EXPECT_NEAR(mean(monteCarloNees(P, 2.0 * P, 20000, 43)), 1.5, 0.05);   // pessimistic filter
  EXPECT_NEAR(mean(monteCarloNees(P, 0.5 * P, 20000, 44)), 6.0, 0.15);   // optimistic filter
}

TEST(Nees, AngleErrorIsWrapped) {
  const Mat3 P = Mat3::Identity() * 0.01;
  EXPECT_NEAR(poseNees(Pose2(0, 0, std::numbers::pi - 0.01), P, Pose2(0, 0, -std::numbers::pi + 0.01)),
              0.02 * 0.02 / 0.01, 1e-9);
}

TEST(Nees, RejectsCovariancesThatAreNotPositiveDefinite) {
  Mat3 singular = Mat3::Zero();
  singular(0, 0) = 1.0;
  EXPECT_THROW(poseNees(Pose2(), singular, Pose2()), std::invalid_argument);
  Mat3 asymmetric = Mat3::Identity();
  asymmetric(0, 1) = 0.5;
  EXPECT_THROW(poseNees(Pose2(), asymmetric, Pose2()), std::invalid_argument);
  EXPECT_THROW(poseNees(Pose2(std::nan(""), 0, 0), Mat3::Identity(), Pose2()), std::invalid_argument);
}

TEST(Nees, SummaryAveragesOverRunsPerStep) {
  const std::vector<std::vector<double>> nees = {{1.0, 3.0, 100.0}, {3.0, 5.0, 100.0}};
  const NeesSummary s = summarizeNees(nees, 3);
  ASSERT_EQ(s.average_per_step.size(), 3u);
  EXPECT_DOUBLE_EQ(s.average_per_step[0], 2.0);
  EXPECT_DOUBLE_EQ(s.average_per_step[1], 4.0);
  EXPECT_NEAR(s.average, 212.0 / 6.0, 1e-12);
  const NeesInterval two_runs = averageNeesInterval(3, 2);
  EXPECT_DOUBLE_EQ(s.step_interval.lower, two_runs.lower);
  EXPECT_NEAR(s.fraction_steps_inside, 2.0 / 3.0, 1e-12);  // 100 is outside
  EXPECT_THROW(summarizeNees({{1.0}, {1.0, 2.0}}, 3), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
