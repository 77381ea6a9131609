// Right-angle corner fit in polar coordinates (thesis §2.4, docs/algorithms.md §16.10) and its covariance of
// apex and orientation γ (docs/algorithms.md §17.8), checked against Monte Carlo estimates.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "laser/corner_fit.hpp"
#include "unit/laser/synthetic_scans.hpp"

namespace polarslam {
namespace {

/// A corner with apex `apex`, free-space bisector γ and arms `arm_length` long; concave arms run
/// along γ ± 45°, convex faces along γ ± 135°.
struct CornerCase {
  Vec2 apex;
  double gamma_deg;
  bool convex;
  double arm_length;
  double step_deg;
};

std::ostream& operator<<(std::ostream& os, const CornerCase& c) {
  return os << "apex " << c.apex.transpose() << " gamma " << c.gamma_deg << (c.convex ? " convex" : " concave");
}

/// Readings of both arms, split by the wall each beam hits.
struct CornerReadings {
  std::vector<double> bearings[2], ranges[2];
};

CornerReadings cornerReadings(const CornerCase& c) {
  const double spread = deg2rad(c.convex ? 135.0 : 45.0);
  const double g = deg2rad(c.gamma_deg);
  const synthetic::Wall walls[2] = {
      {c.apex, c.apex + c.arm_length * Vec2(std::cos(g - spread), std::sin(g - spread))},
      {c.apex, c.apex + c.arm_length * Vec2(std::cos(g + spread), std::sin(g + spread))}};
  CornerReadings out;
  const double step = deg2rad(c.step_deg);
  for (double b = -std::numbers::pi; b < std::numbers::pi; b += step) {
    const double r0 = synthetic::wallRange(walls[0], b), r1 = synthetic::wallRange(walls[1], b);
    if (!std::isfinite(r0) && !std::isfinite(r1)) continue;
    const int arm = r0 < r1 ? 0 : 1;
    out.bearings[arm].push_back(b);
    out.ranges[arm].push_back(std::min(r0, r1));
  }
  return out;
}

const std::vector<CornerCase> kCorners = {
    {{2.0, 2.0}, 225, false, 2.0, 1.0},  {{3.0, -1.0}, 160, false, 1.5, 0.5}, {{1.0, 0.3}, 190, false, 0.6, 0.5},
    {{6.0, 1.0}, 200, false, 3.0, 0.5},  {{2.0, 0.0}, 180, true, 0.8, 0.5},   {{-1.5, 1.5}, -30, true, 1.0, 1.0},
};

TEST(CornerFit, RecoversNoiseFreeCornersAndTheirKind) {
  for (const CornerCase& c : kCorners) {
    SCOPED_TRACE(testing::Message() << c);
    const CornerReadings r = cornerReadings(c);
    ASSERT_GE(r.bearings[0].size(), 5u);
    ASSERT_GE(r.bearings[1].size(), 5u);
    const PolarReadingBuffer arm1(r.bearings[0], r.ranges[0]), arm2(r.bearings[1], r.ranges[1]);
    const CornerFit fit = fitRightAngleCorner(arm1.view(), arm2.view());
    ASSERT_TRUE(fit.ok()) << toString(fit.status);
    EXPECT_NEAR((fit.corner.apex() - c.apex).norm(), 0.0, 1e-8);
    EXPECT_NEAR(wrapAngle(fit.corner.gamma() - deg2rad(c.gamma_deg)), 0.0, 1e-9);
    EXPECT_EQ(fit.convex, c.convex);
    EXPECT_LT(fit.residual_rms, 1e-9);
  }
}

TEST(CornerFit, ArmsOrderDoesNotMatter) {
  const CornerReadings r = cornerReadings(kCorners[1]);
  const PolarReadingBuffer arm1(r.bearings[0], r.ranges[0]), arm2(r.bearings[1], r.ranges[1]);
  const CornerFit a = fitRightAngleCorner(arm1.view(), arm2.view());
  const CornerFit b = fitRightAngleCorner(arm2.view(), arm1.view());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NEAR((a.corner.apex() - b.corner.apex()).norm(), 0.0, 1e-9);
  EXPECT_NEAR(wrapAngle(a.corner.gamma() - b.corner.gamma()), 0.0, 1e-9);
}

TEST(CornerFit, ObservationJacobianMatchesFiniteDifferences) {
  const RightAngleCorner corner{0.7, 2.0, 1.3, -1};
  const Mat3 j = corner.observationJacobian();
  constexpr double kH = 1e-7;
  for (int k = 0; k < 3; ++k) {
    RightAngleCorner plus = corner, minus = corner;
    double* p[3] = {&plus.alpha, &plus.d1, &plus.d2};
    double* m[3] = {&minus.alpha, &minus.d1, &minus.d2};
    *p[k] += kH;
    *m[k] -= kH;
    const Vec3 numeric((plus.apex().x() - minus.apex().x()) / (2 * kH), (plus.apex().y() - minus.apex().y()) / (2 * kH),
                       wrapAngle(plus.gamma() - minus.gamma()) / (2 * kH));
    EXPECT_NEAR((j.col(k) - numeric).norm(), 0.0, 1e-6) << "column " << k;
  }
}

TEST(CornerFit, FailsCleanlyOnTooFewReadings) {
  const std::vector<double> b = {0.1, 0.2};
  const PolarReadingBuffer two(b, std::vector<double>{1.0, 1.0});
  EXPECT_FALSE(fitRightAngleCorner(two.view(), two.view()).ok());
  EXPECT_FALSE(fitRightAngleCorner(PolarReadings{}, two.view()).ok());
}

/// Monte Carlo: empirical std of apex x, y and γ vs J·σ_r²(HᵀH)⁻¹·Jᵀ.
TEST(CornerFit, CovarianceMatchesMonteCarlo) {
  constexpr double kSigma = 0.01;
  constexpr int kTrials = 1000;
  std::mt19937_64 rng(3141);
  std::normal_distribution<double> noise(0.0, kSigma);
  for (const CornerCase& c : kCorners) {
    SCOPED_TRACE(testing::Message() << c);
    const CornerReadings r = cornerReadings(c);
    std::vector<double> noisy[2] = {r.ranges[0], r.ranges[1]};
    Vec3 sum = Vec3::Zero();
    Mat3 outer = Mat3::Zero(), predicted = Mat3::Zero();
    for (int t = 0; t < kTrials; ++t) {
      for (int arm = 0; arm < 2; ++arm)
        for (size_t i = 0; i < noisy[arm].size(); ++i) noisy[arm][i] = r.ranges[arm][i] + noise(rng);
      const PolarReadingBuffer arm1(r.bearings[0], noisy[0]), arm2(r.bearings[1], noisy[1]);
      const CornerFit fit = fitRightAngleCorner(arm1.view(), arm2.view());
      ASSERT_TRUE(fit.ok()) << toString(fit.status);
      const Vec2 apex = fit.corner.apex();
      const Vec3 e(apex.x() - c.apex.x(), apex.y() - c.apex.y(), wrapAngle(fit.corner.gamma() - deg2rad(c.gamma_deg)));
      sum += e;
      outer += e * e.transpose();
      predicted += fit.covariance(kSigma) / kTrials;
    }
    const Vec3 mean = sum / kTrials;
    const Mat3 cov = (outer - kTrials * mean * mean.transpose()) / (kTrials - 1);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(std::sqrt(cov(k, k) / predicted(k, k)), 1.0, 0.10) << "component " << k;
    const double rho = cov(0, 1) / std::sqrt(cov(0, 0) * cov(1, 1));
    const double rho_predicted = predicted(0, 1) / std::sqrt(predicted(0, 0) * predicted(1, 1));
    EXPECT_NEAR(rho, rho_predicted, 0.1) << "x–y correlation";
  }
}

/// Systematic corner errors use the same general projection as lines: a fixed range bias moves the
/// apex as predicted.
TEST(CornerFit, FixedBiasBudgetMatchesSimulation) {
  LaserErrorParams p;
  p.range.fixed_bias = 0.01;
  const LaserErrorModel model(p);
  for (const CornerCase& c : kCorners) {
    SCOPED_TRACE(testing::Message() << c);
    const CornerReadings r = cornerReadings(c);
    std::vector<double> biased[2] = {r.ranges[0], r.ranges[1]};
    for (auto& arm : biased)
      for (double& x : arm) x += p.range.fixed_bias;
    const PolarReadingBuffer exact1(r.bearings[0], r.ranges[0]), exact2(r.bearings[1], r.ranges[1]);
    const PolarReadingBuffer biased1(r.bearings[0], biased[0]), biased2(r.bearings[1], biased[1]);
    const CornerFit truth = fitRightAngleCorner(exact1.view(), exact2.view());
    const CornerFit fit = fitRightAngleCorner(biased1.view(), biased2.view());
    ASSERT_TRUE(truth.ok() && fit.ok());
    const Vec3 simulated((fit.corner.apex() - c.apex).cwiseAbs().x(), (fit.corner.apex() - c.apex).cwiseAbs().y(),
                         std::abs(wrapAngle(fit.corner.gamma() - truth.corner.gamma())));
    const CornerErrorBudget budget = cornerErrorBudget(truth, exact1.view(), exact2.view(), {}, {}, model);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(budget.systematic_bound(k), simulated(k), 0.10 * simulated(k) + 1e-9) << "component " << k;
    EXPECT_TRUE(budget.filterCov().isApprox(budget.randomCov() + Mat3(budget.systematic_bound.array().square().matrix().asDiagonal())));
  }
}

}  // namespace
}  // namespace polarslam
