// Systematic and per-scan line errors (thesis §2.3.4–§2.3.10, App. A.3–A.6): each formula is
// checked against a simulation in which only its own error source is switched on.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "laser/line_errors.hpp"
#include "unit/laser/synthetic_scans.hpp"

namespace polarslam {
namespace {

/// A line (α, d) seen over `extent` degrees of bearings centred `offset` degrees off its normal.
struct LineCase {
  double alpha_deg, d, offset_deg, extent_deg, step_deg;

  PolarLine line() const { return {deg2rad(alpha_deg), d}; }
  /// Position t_c of the segment's centre along the line, from the foot of the normal.
  double lever() const { return d * std::tan(deg2rad(offset_deg)); }
  std::vector<double> bearings() const {
    const double centre = deg2rad(alpha_deg + offset_deg);
    const int n = static_cast<int>(std::round(extent_deg / step_deg)) + 1;
    return synthetic::bearings(centre - deg2rad(extent_deg) / 2, centre + deg2rad(extent_deg) / 2, n);
  }
};

std::ostream& operator<<(std::ostream& os, const LineCase& c) {
  return os << "alpha " << c.alpha_deg << " d " << c.d << " offset " << c.offset_deg << " extent " << c.extent_deg;
}

const std::vector<LineCase> kCases = {
    {90, 1.0, 0, 60, 1},    {0, 0.5, 30, 40, 0.5},  {-135, 2.0, -40, 50, 1}, {45, 4.0, 50, 20, 0.5},
    {170, 8.0, -10, 10, 0.25}, {-60, 1.5, 20, 100, 1}, {120, 3.0, 0, 30, 1},
};

/// Fitted (α, d) error when the ranges of `truth` at `bearings` are replaced by `ranges`.
Vec2 fittedError(const PolarLine& truth, const std::vector<double>& bearings, const std::vector<double>& ranges) {
  const PolarReadingBuffer readings(bearings, ranges);
  const LineFit fit = fitLinePolar(readings.view());
  EXPECT_TRUE(fit.ok()) << toString(fit.status);
  return {wrapAngle(fit.line.alpha - truth.alpha), fit.line.d - truth.d};
}

/// The predicted (Δα, Δd) within `rel` of the simulated error. For d the allowance also counts
/// rel·|t_c·Δα|: the part of a line's distance error that follows from its angle error where the
/// segment is (otherwise a tiny Δd of a far, oblique segment would have to be matched to a few
/// micrometres). `abs_allowance` covers components that are zero by symmetry.
void expectAgrees(const Vec2& predicted, const Vec2& simulated, double rel, double lever = 0.0,
                  double abs_allowance = 1e-9) {
  EXPECT_NEAR(predicted.x(), simulated.x(), rel * std::abs(simulated.x()) + abs_allowance)
      << "alpha: predicted " << predicted.transpose() << " simulated " << simulated.transpose();
  EXPECT_NEAR(predicted.y(), simulated.y(),
              rel * (std::abs(simulated.y()) + std::abs(lever * simulated.x())) + abs_allowance)
      << "d: predicted " << predicted.transpose() << " simulated " << simulated.transpose();
}

TEST(LineErrors, GeneralFormIsOneGaussNewtonStep) {
  // A small arbitrary perturbation: the general (A.29)–(A.30) form equals the fit's change.
  const LineCase c{30, 2.0, 15, 50, 0.5};
  const std::vector<double> b = c.bearings();
  std::vector<double> r = synthetic::lineRanges(c.line(), b);
  std::vector<double> xi(b.size());
  for (size_t i = 0; i < b.size(); ++i) xi[i] = 1e-4 * std::sin(7.0 * b[i]) + 5e-5 * static_cast<double>(i % 3);
  for (size_t i = 0; i < b.size(); ++i) r[i] += xi[i];
  const PolarReadingBuffer exact(b, synthetic::lineRanges(c.line(), b));
  expectAgrees(lineErrorFromRangeErrors(c.line(), exact.view(), xi), fittedError(c.line(), b, r), 0.01, c.lever());
}

TEST(LineErrors, FixedBiasMatchesSimulation) {
  constexpr double kBias = 0.02;
  for (const LineCase& c : kCases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> biased = exact;
    for (double& r : biased) r += kBias;
    const Vec2 simulated = fittedError(c.line(), b, biased);
    const PolarReadingBuffer readings(b, exact);
    expectAgrees(fixedBiasLineErrorGeneral(c.line(), readings.view(), kBias), simulated, 0.05, c.lever());
    if (c.extent_deg / 2 + std::abs(c.offset_deg) <= 60) {  // validity of the regression form
      expectAgrees(fixedBiasLineError(c.line(), readings.view(), kBias), simulated, 0.10, c.lever());
    }
  }
}

TEST(LineErrors, ThesisFixedBiasFormLosesAccuracyBeyondSixtyDegrees) {
  // Documented approximation limit of (2.33)/(2.35): a symmetric view over ±75°.
  const LineCase c{90, 1.0, 0, 150, 1};
  const std::vector<double> b = c.bearings();
  const PolarReadingBuffer readings(b, synthetic::lineRanges(c.line(), b));
  const double thesis = fixedBiasLineError(c.line(), readings.view(), 0.01).y();
  const double general = fixedBiasLineErrorGeneral(c.line(), readings.view(), 0.01).y();
  EXPECT_GT(thesis / general, 1.2);
}

/// Per-scan random bias: Monte Carlo covariance of the fitted line vs (A.21) with the d′ factor.
TEST(LineErrors, PerScanBiasCovarianceMatchesMonteCarlo) {
  constexpr double kBiasSigma = 0.01;
  constexpr int kTrials = 1000;
  std::mt19937_64 rng(4242);
  std::normal_distribution<double> bias(0.0, kBiasSigma);
  for (const LineCase& c : kCases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    Mat2 outer = Mat2::Zero();
    std::vector<double> ranges(exact.size());
    for (int t = 0; t < kTrials; ++t) {
      const double rb = bias(rng);
      for (size_t i = 0; i < exact.size(); ++i) ranges[i] = exact[i] + rb;
      const Vec2 e = fittedError(c.line(), b, ranges);
      outer += e * e.transpose() / kTrials;
    }
    const PolarReadingBuffer readings(b, exact);
    const Mat2 general = scanBiasCovarianceGeneral(c.line(), readings.view(), kBiasSigma);
    const Mat2 thesis = scanBiasCovariance(c.line(), readings.view(), kBiasSigma);
    for (int k = 0; k < 2; ++k) {
      if (general(k, k) < 1e-14) continue;  // α error zero by symmetry
      EXPECT_NEAR(std::sqrt(outer(k, k) / general(k, k)), 1.0, 0.10) << "general, component " << k;
      if (c.extent_deg / 2 + std::abs(c.offset_deg) <= 60) {
        EXPECT_NEAR(std::sqrt(outer(k, k) / thesis(k, k)), 1.0, 0.10) << "(A.21), component " << k;
      }
    }
  }
}

TEST(LineErrors, ExcerptsScanBiasFormWithoutDistanceFactorIsWrong) {
  // docs/algorithms.md §16.5: D = (1/n)Σcot φ (excerpt) instead of D′ = (d/n)Σcot φ. At d = 4 m the two
  // differ; the corrected one matches the general form.
  const LineCase c{45, 4.0, 30, 30, 0.5};
  const std::vector<double> b = c.bearings();
  const PolarReadingBuffer readings(b, synthetic::lineRanges(c.line(), b));
  const Mat2 corrected = scanBiasCovariance(c.line(), readings.view(), 1.0);
  const Mat2 general = scanBiasCovarianceGeneral(c.line(), readings.view(), 1.0);
  EXPECT_NEAR(corrected(1, 1) / general(1, 1), 1.0, 0.05);
  double sum_cot = 0.0, sum_cos = 0.0, sum_sin = 0.0, sum_cot2 = 0.0;
  for (double bearing : b) {
    const double phi = normalizedBearing(c.line(), bearing);
    sum_cot += 1.0 / std::tan(phi);
    sum_cot2 += 1.0 / std::pow(std::tan(phi), 2);
    sum_cos += std::cos(phi);
    sum_sin += std::sin(phi);
  }
  const double n = static_cast<double>(b.size());
  const double A = (n * sum_cos - sum_cot * sum_sin) / (c.d * (n * sum_cot2 - sum_cot * sum_cot));
  const double excerpt_q = sum_sin / n - A * sum_cot / n;
  EXPECT_GT(std::abs(excerpt_q * excerpt_q / general(1, 1) - 1.0), 0.2);
}

TEST(LineErrors, IncidenceAngleErrorMatchesSimulation) {
  constexpr double kW = 0.01;
  for (const LineCase& c : kCases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> ranges = exact;
    for (size_t i = 0; i < b.size(); ++i) ranges[i] += kW * std::abs(std::tan(c.line().alpha - b[i]));  // (2.8)
    const Vec2 simulated = fittedError(c.line(), b, ranges);
    const PolarReadingBuffer readings(b, exact);
    expectAgrees(incidenceAngleLineError(c.line(), readings.view(), kW), simulated, 0.10, c.lever());
    expectAgrees(incidenceAngleLineErrorClosedForm(c.line(), readings.view(), kW), simulated, 0.10, c.lever());
  }
}

TEST(LineErrors, IncidenceAngleClosedFormCoversAllThreeSignCases) {
  // Normal inside the view (s = t = 1), view entirely on one side (t = −1), and on the other (s = −1).
  const PolarLine line{deg2rad(90), 2.0};
  for (const auto& [first, last] : {std::pair{60.0, 130.0}, std::pair{20.0, 80.0}, std::pair{100.0, 160.0}}) {
    const std::vector<double> b = synthetic::bearings(deg2rad(first), deg2rad(last), 141);
    const PolarReadingBuffer readings(b, synthetic::lineRanges(line, b));
    expectAgrees(incidenceAngleLineErrorClosedForm(line, readings.view(), 0.01),
                 incidenceAngleLineError(line, readings.view(), 0.01, 1.5), 0.02);
  }
}

TEST(LineErrors, DistanceGrowthErrorMatchesSimulation) {
  constexpr double kK = 0.01;
  for (const LineCase& c : kCases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    const double r_min = *std::min_element(exact.begin(), exact.end());
    std::vector<double> ranges = exact;
    for (double& r : ranges) r += kK * (r - r_min);  // (2.8)
    const Vec2 simulated = fittedError(c.line(), b, ranges);
    const PolarReadingBuffer readings(b, exact);
    expectAgrees(distanceGrowthLineError(c.line(), readings.view(), kK), simulated, 0.10, c.lever());
    expectAgrees(distanceGrowthLineErrorClosedForm(c.line(), readings.view(), kK), simulated, 0.10, c.lever());
  }
}

/// Quantisation: the real truncating quantiser with noise (2.1)–(2.5), averaged over many scans
/// (with the constant −q/2 removed, as (2.8) does), vs the error predicted from (2.6). A noisy
/// short line's fit has a second-order bias of its own (E[d̂] ≈ d − d·σ_α²/2), so the simulated
/// quantisation error is measured against a control run with Gaussian noise of the quantiser's
/// output standard deviation, the same bearings and as many scans.
TEST(LineErrors, QuantizationBiasMatchesQuantizerMonteCarlo) {
  constexpr double kQuantum = 0.05, kNoise = 0.017;  // the SICK PLS of fig. 2.3
  constexpr int kTrials = 2000;
  LaserErrorParams params;
  params.range.quantum = kQuantum;
  params.range.noise_sigma = kNoise;
  const LaserErrorModel model(params);
  std::mt19937_64 rng(99);
  std::normal_distribution<double> input_noise(0.0, kNoise), output_noise(0.0, model.rangeSigma());
  // Views where the ranges stay within a fraction of a step, so that the bias is coherent.
  const std::vector<LineCase> cases = {{90, 2.012, 0, 12, 0.1}, {90, 1.012, 0, 20, 0.25}, {-100, 3.04, 4, 8, 0.1}};
  for (const LineCase& c : cases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    Vec2 mean = Vec2::Zero(), mean_sq = Vec2::Zero();
    std::vector<double> quantized(exact.size()), control(exact.size());
    for (int t = 0; t < kTrials; ++t) {
      for (size_t i = 0; i < exact.size(); ++i) {
        quantized[i] = quantize(exact[i] + input_noise(rng), kQuantum) + kQuantum / 2;  // (2.1)
        control[i] = exact[i] + output_noise(rng);
      }
      const Vec2 e = fittedError(c.line(), b, quantized) - fittedError(c.line(), b, control);
      mean += e / kTrials;
      mean_sq += e.cwiseProduct(e) / kTrials;
    }
    const Vec2 standard_error = ((mean_sq - mean.cwiseProduct(mean)) / kTrials).cwiseSqrt();
    const PolarReadingBuffer readings(b, exact);
    const Vec2 predicted = quantizationLineError(c.line(), readings.view(), kQuantum, model.quantizationAmplitude());
    ASSERT_GT(mean.cwiseQuotient(standard_error).cwiseAbs().maxCoeff(), 10.0) << "choose a case with a visible bias";
    for (int k = 0; k < 2; ++k)
      EXPECT_NEAR(predicted[k], mean[k], 0.10 * std::abs(mean[k]) + 3 * standard_error[k]) << "component " << k;
    const Vec2 bound =
        quantizationLineErrorBound(c.line(), readings.view(), kQuantum, model.quantizationAmplitude());
    EXPECT_TRUE((bound.array() >= predicted.array().abs() - 1e-12).all());
  }
}

TEST(LineErrors, QuantizationBoundHoldsForAnyPhase) {
  // The same line shifted by fractions of a step: the deterministic error never exceeds the bound.
  constexpr double kQuantum = 0.01, kAmplitude = 0.003;
  for (double shift = 0.0; shift < kQuantum; shift += kQuantum / 7) {
    const LineCase c{20, 1.5 + shift, 10, 30, 0.5};
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> ranges = exact;
    for (double& r : ranges) r += quantizationPerturbation(r, kQuantum, kAmplitude);
    const Vec2 simulated = fittedError(c.line(), b, ranges);
    const PolarReadingBuffer readings(b, exact);
    expectAgrees(quantizationLineError(c.line(), readings.view(), kQuantum, kAmplitude), simulated, 0.10, c.lever(), 1e-7);
    const Vec2 bound = quantizationLineErrorBound(c.line(), readings.view(), kQuantum, kAmplitude);
    EXPECT_LE(std::abs(simulated.x()), bound.x() * 1.05);
    EXPECT_LE(std::abs(simulated.y()), bound.y() * 1.05);
  }
}

/// Exact geometry of a tilted scan plane: the beam at encoder angle φ is rotated by ε about the
/// horizontal axis at bearing ψ and meets the vertical wall x cos α + y sin α = d.
double tiltedBeamRange(const PolarLine& wall, double bearing, double tilt, double axis) {
  const Eigen::Vector3d beam = Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis), std::sin(axis), 0.0)) *
                               Eigen::Vector3d(std::cos(bearing), std::sin(bearing), 0.0);
  return wall.d / Eigen::Vector3d(std::cos(wall.alpha), std::sin(wall.alpha), 0.0).dot(beam);
}

TEST(LineErrors, PlaneTiltMatchesRayCastingThroughTiltedPlane) {
  constexpr double kTilt = deg2rad(2.0);
  for (double axis_deg : {0.0, 37.0, 90.0, -120.0}) {
    for (const LineCase& c : kCases) {
      SCOPED_TRACE(testing::Message() << c << " axis " << axis_deg);
      const std::vector<double> b = c.bearings();
      std::vector<double> ranges(b.size());
      for (size_t i = 0; i < b.size(); ++i) ranges[i] = tiltedBeamRange(c.line(), b[i], kTilt, deg2rad(axis_deg));
      const Vec2 simulated = fittedError(c.line(), b, ranges);
      const PolarReadingBuffer readings(b, synthetic::lineRanges(c.line(), b));
      expectAgrees(planeTiltLineError(c.line(), readings.view(), kTilt, deg2rad(axis_deg)), simulated, 0.10, c.lever(), 1e-8);
    }
  }
  // Notes §16.10's r·e²/2 would predict an error for a wall facing along the tilt axis; there is none.
  const LineCase facing{0, 2.0, 0, 60, 1};
  const std::vector<double> b = facing.bearings();
  std::vector<double> ranges(b.size());
  for (size_t i = 0; i < b.size(); ++i) ranges[i] = tiltedBeamRange(facing.line(), b[i], kTilt, 0.0);
  EXPECT_LT(fittedError(facing.line(), b, ranges).norm(), 1e-9);
}

TEST(LineErrors, YawMisalignmentTurnsTheLine) {
  constexpr double kYaw = deg2rad(0.5);
  const LineCase c{60, 2.0, 10, 40, 0.5};
  std::vector<double> b = c.bearings();
  const std::vector<double> ranges = synthetic::lineRanges(c.line(), b);
  for (double& bearing : b) bearing += kYaw;  // the laser reports bearings turned by δ
  const PolarReadingBuffer readings(b, ranges);
  const LineFit fit = fitLinePolar(readings.view());
  ASSERT_TRUE(fit.ok());
  expectAgrees(yawMisalignmentLineError(kYaw), {wrapAngle(fit.line.alpha - c.line().alpha), fit.line.d - c.d}, 1e-6, 0.0, 1e-9);
}

/// Exact constant-twist motion during the scan: reading i is taken from the pose reached after
/// τ_i seconds; the fit treats all readings as taken from the reference pose.
TEST(LineErrors, MotionDuringScanMatchesExactMotion) {
  const std::vector<SensorMotion> motions = {{1.0, 0.0, 0.0}, {0.0, 0.0, 1.5}, {0.8, 0.2, -1.0}};
  constexpr double kBeamTime = 1e-4;  // s per beam
  for (const SensorMotion& m : motions) {
    for (const LineCase& c : kCases) {
      SCOPED_TRACE(testing::Message() << c << " motion " << m.vx << " " << m.vy << " " << m.omega);
      const std::vector<double> b = c.bearings();
      std::vector<double> times(b.size()), ranges(b.size());
      for (size_t i = 0; i < b.size(); ++i) {
        times[i] = kBeamTime * static_cast<double>(i);
        const double turn = m.omega * times[i];
        // SE(2) exponential of the body twist over τ.
        const double a = std::abs(turn) < 1e-12 ? 1.0 : std::sin(turn) / turn;
        const double bb = std::abs(turn) < 1e-12 ? 0.0 : (1.0 - std::cos(turn)) / turn;
        const Pose2 pose(times[i] * (a * m.vx - bb * m.vy), times[i] * (bb * m.vx + a * m.vy), turn);
        const PolarLine seen{c.line().alpha - pose.theta,
                             c.d - std::cos(c.line().alpha) * pose.x - std::sin(c.line().alpha) * pose.y};
        ranges[i] = lineRange(seen, b[i]);
      }
      const Vec2 simulated = fittedError(c.line(), b, ranges);
      const PolarReadingBuffer readings(b, synthetic::lineRanges(c.line(), b));
      expectAgrees(motionLineError(c.line(), readings.view(), times, m), simulated, 0.10, c.lever(), 1e-8);
    }
  }
}

TEST(LineErrors, BudgetSumsAbsoluteValuesAndBoundsAllSourcesTogether) {
  LaserErrorParams p;
  p.range.noise_sigma = 0.01;
  p.range.scan_bias_sigma = 0.005;
  p.range.fixed_bias = 0.01;
  p.range.growth = 0.005;
  p.range.incidence = 0.004;
  p.range.quantum = 0.01;
  p.tilt = deg2rad(1.0);
  p.tilt_axis = deg2rad(30);
  p.yaw_error = deg2rad(0.1);
  const LaserErrorModel model(p);
  const SensorMotion motion{0.5, 0.0, 0.5};
  for (const LineCase& c : kCases) {
    SCOPED_TRACE(testing::Message() << c);
    const std::vector<double> b = c.bearings();
    const std::vector<double> exact = synthetic::lineRanges(c.line(), b);
    std::vector<double> times(b.size());
    for (size_t i = 0; i < b.size(); ++i) times[i] = 2e-5 * static_cast<double>(i);
    const PolarReadingBuffer readings(b, exact);
    const LineFit fit = fitLinePolar(readings.view());
    ASSERT_TRUE(fit.ok());
    const LineErrorBudget budget = lineErrorBudget(fit, readings.view(), times, model, motion);
    const Vec2 sum = budget.fixed_bias.cwiseAbs() + budget.incidence.cwiseAbs() + budget.growth.cwiseAbs() +
                     budget.quantization.cwiseAbs() + budget.plane_tilt.cwiseAbs() + budget.yaw.cwiseAbs() +
                     budget.motion.cwiseAbs();
    EXPECT_NEAR((budget.systematic_bound - sum).norm(), 0.0, 1e-15);
    // The budget's single pass gives the same numbers as each source's own function.
    const PolarReadings v = readings.view();
    auto same = [](const Vec2& a, const Vec2& b) { return (a - b).norm() <= 1e-9 * (1.0 + b.norm()) + 1e-15; };
    EXPECT_TRUE(same(budget.fixed_bias, fixedBiasLineErrorGeneral(fit.line, v, p.range.fixed_bias)));
    EXPECT_TRUE(same(budget.incidence, incidenceAngleLineError(fit.line, v, p.range.incidence, p.range.max_incidence)));
    EXPECT_TRUE(same(budget.growth, distanceGrowthLineError(fit.line, v, p.range.growth)));
    EXPECT_TRUE(same(budget.quantization,
                     quantizationLineErrorBound(fit.line, v, p.range.quantum, model.quantizationAmplitude())));
    EXPECT_TRUE(same(budget.plane_tilt, planeTiltLineError(fit.line, v, p.tilt, p.tilt_axis)));
    EXPECT_TRUE(same(budget.motion, motionLineError(fit.line, v, times, motion)));
    EXPECT_TRUE(budget.scan_bias_cov.isApprox(scanBiasCovarianceGeneral(fit.line, v, p.range.scan_bias_sigma), 1e-9));
    EXPECT_TRUE(budget.noise_cov.isApprox(fit.covariance(model.rangeSigma())));
    const Mat2 filter = budget.filterCov();
    EXPECT_NEAR(filter(0, 0), budget.randomCov()(0, 0) + std::pow(budget.systematic_bound.x(), 2), 1e-15);
    EXPECT_NEAR(filter(0, 1), budget.randomCov()(0, 1), 1e-15);

    // Superposition (docs/algorithms.md §19.1): all systematic sources at once stay within the bound.
    std::vector<double> ranges(b.size());
    const double r_min = *std::min_element(exact.begin(), exact.end());
    for (size_t i = 0; i < b.size(); ++i) {
      const double r = exact[i];
      ranges[i] = tiltedBeamRange(c.line(), b[i], p.tilt, p.tilt_axis) + p.range.fixed_bias +
                  p.range.growth * (r - r_min) + incidenceAnglePerturbation(c.line().alpha, b[i], p.range.incidence, 1.4) +
                  quantizationPerturbation(r, p.range.quantum, model.quantizationAmplitude()) +
                  motionPerturbation(c.line().alpha, c.d, b[i], times[i], motion);
    }
    std::vector<double> turned = b;
    for (double& bearing : turned) bearing += p.yaw_error;
    const Vec2 simulated = fittedError(c.line(), turned, ranges);
    EXPECT_LE(std::abs(simulated.x()), budget.systematic_bound.x() * 1.02);
    EXPECT_LE(std::abs(simulated.y()), budget.systematic_bound.y() * 1.02);
  }
}

TEST(LaserErrorModel, RangeSigmaCombinesNoiseAndQuantizer) {
  LaserErrorParams p;
  p.range.noise_sigma = 0.017;
  EXPECT_DOUBLE_EQ(LaserErrorModel(p).rangeSigma(), 0.017);
  p.range.quantum = 0.05;
  const LaserErrorModel quantized(p);
  // Averaged over the phase, the quantiser's output variance (2.5) exceeds the input noise's.
  EXPECT_GT(quantized.rangeSigma(), 0.017);
  EXPECT_LT(quantized.rangeSigma(), std::sqrt(0.017 * 0.017 + 0.05 * 0.05 / 12) * 1.05);
  EXPECT_GT(quantized.quantizationAmplitude(), 0.0);
  p.range = {};
  EXPECT_DOUBLE_EQ(LaserErrorModel(p).rangeSigma(), p.min_range_sigma);
}

TEST(LaserErrorModel, SensorMotionOfAnOffsetMount) {
  // Laser 0.3 m ahead, turned 90° left; base turning on the spot at 1 rad/s: the laser moves
  // along the base's +y at 0.3 m/s, which is the laser's own +x.
  const SensorMotion m = sensorMotionFromBaseTwist(Pose2(0.3, 0.0, std::numbers::pi / 2), 0.0, 1.0);
  EXPECT_NEAR(m.vx, 0.3, 1e-12);
  EXPECT_NEAR(m.vy, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.omega, 1.0);
}

}  // namespace
}  // namespace polarslam
