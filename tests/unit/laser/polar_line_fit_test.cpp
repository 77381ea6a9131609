// Polar line fit (2.16)–(2.23) and its random covariance σ_r²(HᵀH)⁻¹ (2.25), checked against
// Monte Carlo estimates over noisy analytic lines, and against a Cartesian TLS fit.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "laser/polar_line_fit.hpp"
#include "unit/laser/synthetic_scans.hpp"

namespace polarslam {
namespace {

/// A line seen over a span of bearings: normal α, distance d, bearings centred at α + offset.
struct LineView {
  double alpha, d, offset_deg, extent_deg, step_deg;

  std::vector<double> bearings() const {
    const double centre = alpha + deg2rad(offset_deg);
    const int n = static_cast<int>(std::round(extent_deg / step_deg)) + 1;
    return synthetic::bearings(centre - deg2rad(extent_deg) / 2, centre + deg2rad(extent_deg) / 2, n);
  }
};

/// Sample statistics of the fitted (α, d) errors over many noisy scans.
struct ErrorSample {
  Vec2 mean = Vec2::Zero();
  Mat2 cov = Mat2::Zero();
  Vec2 rmse = Vec2::Zero();
};

class ErrorAccumulator {
 public:
  void add(const Vec2& e) {
    sum_ += e;
    outer_ += e * e.transpose();
    ++n_;
  }
  ErrorSample sample() const {
    ErrorSample s;
    s.mean = sum_ / n_;
    s.cov = (outer_ - n_ * s.mean * s.mean.transpose()) / (n_ - 1);
    s.rmse = (outer_.diagonal() / n_).cwiseSqrt();
    return s;
  }

 private:
  Vec2 sum_ = Vec2::Zero();
  Mat2 outer_ = Mat2::Zero();
  double n_ = 0;
};

Vec2 lineError(const PolarLine& fitted, const PolarLine& truth) {
  return {wrapAngle(fitted.alpha - truth.alpha), fitted.d - truth.d};
}

TEST(PolarLineFit, RecoversNoiseFreeLinesOfAnyOrientation) {
  for (double alpha_deg : {-179.0, -135.0, -90.0, -10.0, 0.0, 45.0, 90.0, 180.0}) {
    for (double d : {0.05, 0.5, 3.0, 8.0}) {
      const LineView view{deg2rad(alpha_deg), d, 20.0, 60.0, 1.0};
      const std::vector<double> b = view.bearings();
      const PolarReadingBuffer readings(b, synthetic::lineRanges({view.alpha, d}, b));
      const LineFit fit = fitLinePolar(readings.view());
      ASSERT_TRUE(fit.ok()) << toString(fit.status);
      EXPECT_NEAR(wrapAngle(fit.line.alpha - view.alpha), 0.0, 1e-9) << alpha_deg << " " << d;
      EXPECT_NEAR(fit.line.d, d, 1e-9);
      EXPECT_LT(fit.residual_rms, 1e-9);
      EXPECT_TRUE(fit.converged);
    }
  }
}

TEST(PolarLineFit, TotalLeastSquaresGivesNormalFormWithPositiveDistance) {
  const std::vector<double> b = synthetic::bearings(deg2rad(100), deg2rad(150), 30);
  const PolarLine truth{deg2rad(125), 2.0};
  const PolarReadingBuffer readings(b, synthetic::lineRanges(truth, b));
  const PolarLine tls = fitLineTotalLeastSquares(readings.view());
  EXPECT_NEAR(wrapAngle(tls.alpha - truth.alpha), 0.0, 1e-9);
  EXPECT_NEAR(tls.d, 2.0, 1e-9);
}

TEST(PolarLineFit, RejectsBeamsNearlyParallelToTheLine) {
  // A wall at d = 1 m seen from 0° to 84° off its normal.
  const std::vector<double> b = synthetic::bearings(deg2rad(0), deg2rad(84), 85);
  const PolarReadingBuffer readings(b, synthetic::lineRanges({0.0, 1.0}, b));
  EXPECT_EQ(fitLinePolar(readings.view()).status, LineFitStatus::GrazingBeam);
  LineFitOptions wide;
  wide.max_incidence = deg2rad(85);
  EXPECT_TRUE(fitLinePolar(readings.view(), wide).ok());
}

TEST(PolarLineFit, FailsCleanlyOnDegenerateInput) {
  EXPECT_EQ(fitLinePolar(PolarReadings{}).status, LineFitStatus::TooFewPoints);
  const std::vector<double> b = {0.1, 0.2};
  const PolarReadingBuffer two(b, std::vector<double>{1.0, 1.0});
  EXPECT_FALSE(fitLinePolar(two.view()).ok());
  const std::vector<double> same = {0.3, 0.3, 0.3};
  const PolarReadingBuffer stacked(same, std::vector<double>{1.0, 1.0, 1.0});
  EXPECT_FALSE(fitLinePolar(stacked.view()).ok());
}

/// Monte Carlo: empirical std of α and d over noisy scans vs σ_r²(HᵀH)⁻¹ (2.25).
TEST(PolarLineFit, RandomCovarianceMatchesMonteCarlo) {
  constexpr double kSigma = 0.01;
  constexpr int kTrials = 1000;
  std::mt19937_64 rng(20250301);
  std::normal_distribution<double> noise(0.0, kSigma);
  const std::vector<LineView> views = {
      {deg2rad(90), 0.5, 0, 90, 1},   {deg2rad(30), 0.5, 40, 60, 0.5}, {deg2rad(-60), 1.0, -20, 40, 1},
      {deg2rad(0), 2.0, 0, 20, 0.5},  {deg2rad(170), 2.0, 50, 40, 1},  {deg2rad(-120), 4.0, 10, 10, 0.5},
      {deg2rad(45), 4.0, -60, 20, 1}, {deg2rad(100), 8.0, 0, 5, 0.25}, {deg2rad(-10), 8.0, 30, 15, 0.5},
  };
  for (const LineView& view : views) {
    SCOPED_TRACE(testing::Message() << "alpha " << rad2deg(view.alpha) << " d " << view.d << " offset "
                                    << view.offset_deg << " extent " << view.extent_deg);
    const PolarLine truth{view.alpha, view.d};
    const std::vector<double> b = view.bearings();
    const std::vector<double> exact = synthetic::lineRanges(truth, b);
    ErrorAccumulator errors;
    Mat2 predicted = Mat2::Zero();
    std::vector<double> ranges(exact.size());
    for (int trial = 0; trial < kTrials; ++trial) {
      for (size_t i = 0; i < exact.size(); ++i) ranges[i] = exact[i] + noise(rng);
      const PolarReadingBuffer readings(b, ranges);
      const LineFit fit = fitLinePolar(readings.view());
      ASSERT_TRUE(fit.ok());
      errors.add(lineError(fit.line, truth));
      predicted += fit.covariance(kSigma) / kTrials;  // (2.25), as a filter would see it
    }
    const ErrorSample s = errors.sample();
    EXPECT_NEAR(std::sqrt(s.cov(0, 0)) / std::sqrt(predicted(0, 0)), 1.0, 0.10) << "alpha";
    EXPECT_NEAR(std::sqrt(s.cov(1, 1)) / std::sqrt(predicted(1, 1)), 1.0, 0.10) << "d";
    const double rho_empirical = s.cov(0, 1) / std::sqrt(s.cov(0, 0) * s.cov(1, 1));
    const double rho_predicted = predicted(0, 1) / std::sqrt(predicted(0, 0) * predicted(1, 1));
    EXPECT_NEAR(rho_empirical, rho_predicted, 0.1) << "correlation";
  }
}

/// The polar fit (maximum likelihood for range noise) is at least as accurate as a Cartesian
/// total-least-squares fit of the same points, and clearly better on oblique lines.
TEST(PolarLineFit, AtLeastAsAccurateAsCartesianTotalLeastSquares) {
  constexpr double kSigma = 0.02;
  constexpr int kTrials = 1000;
  std::mt19937_64 rng(77);
  std::normal_distribution<double> noise(0.0, kSigma);
  struct Case {
    LineView view;
    double min_gain;  ///< required TLS RMSE / polar RMSE, for d
  };
  const std::vector<Case> cases = {
      {{deg2rad(90), 1.0, 0, 60, 1}, 1.0},   {{deg2rad(20), 2.0, 30, 40, 0.5}, 1.0},
      {{deg2rad(-45), 1.0, 45, 60, 1}, 1.1}, {{deg2rad(135), 0.5, -40, 70, 1}, 1.1},
      {{deg2rad(0), 4.0, 0, 10, 0.5}, 1.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << "alpha " << rad2deg(c.view.alpha) << " d " << c.view.d << " offset "
                                    << c.view.offset_deg << " extent " << c.view.extent_deg);
    const PolarLine truth{c.view.alpha, c.view.d};
    const std::vector<double> b = c.view.bearings();
    const std::vector<double> exact = synthetic::lineRanges(truth, b);
    ErrorAccumulator polar, tls;
    std::vector<double> ranges(exact.size());
    for (int trial = 0; trial < kTrials; ++trial) {
      for (size_t i = 0; i < exact.size(); ++i) ranges[i] = exact[i] + noise(rng);
      const PolarReadingBuffer readings(b, ranges);
      const LineFit fit = fitLinePolar(readings.view());
      ASSERT_TRUE(fit.ok());
      polar.add(lineError(fit.line, truth));
      tls.add(lineError(fitLineTotalLeastSquares(readings.view()), truth));
    }
    const Vec2 polar_rmse = polar.sample().rmse, tls_rmse = tls.sample().rmse;
    EXPECT_LE(polar_rmse.x(), tls_rmse.x() * 1.01) << "alpha";
    EXPECT_LE(polar_rmse.y(), tls_rmse.y() * 1.01) << "d";
    EXPECT_GE(tls_rmse.y() / polar_rmse.y(), c.min_gain) << "d";
  }
}

}  // namespace
}  // namespace polarslam
