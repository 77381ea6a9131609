// The simulated laser against the range error model's own closed forms: (2.1)–(2.7) for the
// quantiser, the systematic terms of (2.8), plane tilt and motion distortion.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "laser/range_error_model.hpp"
#include "sim/laser_simulator.hpp"
#include "sim/random.hpp"
#include "sim_test_helpers.hpp"

namespace polarslam {
namespace {

struct Moments {
  double mean = 0.0, variance = 0.0;
};

Moments moments(const std::vector<double>& x) {
  Moments m;
  m.mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  for (double v : x) m.variance += (v - m.mean) * (v - m.mean);
  m.variance /= static_cast<double>(x.size() - 1);
  return m;
}

// ---------------------------------------------------------------------------------------------
// The closed forms themselves (core/laser/range_error_model)

TEST(RangeErrorModel, QuantizerWithoutNoiseIsPlainTruncation) {
  for (double r : {1.003, 1.0099, 2.345}) {  // (not on a step: there noise decides the output)
    EXPECT_NEAR(quantizerMeanError(r, 0.01, 0.0), quantize(r, 0.01) - r, 1e-15);
    EXPECT_NEAR(quantizerMeanError(r, 0.01, 1e-7), quantize(r, 0.01) - r, 1e-9) << r;
    EXPECT_NEAR(quantizerErrorVariance(r, 0.01, 0.0), 0.0, 1e-15);
  }
  EXPECT_DOUBLE_EQ(quantize(1.2345, 0.01), 1.23);
  EXPECT_DOUBLE_EQ(quantize(-0.001, 0.01), -0.01);  // truncation towards −∞ (floor)
}

TEST(RangeErrorModel, WideNoiseGivesHalfStepOffsetAndSheppardVariance) {
  // σ ≫ q: mean error → −q/2 and variance → σ² + q²/12 (Sheppard's correction).
  const double q = 0.01, sigma = 0.05;
  for (double r : {3.0, 3.0031, 3.0077}) {
    EXPECT_NEAR(quantizerMeanError(r, q, sigma), -q / 2, 1e-9);
    EXPECT_NEAR(quantizerErrorVariance(r, q, sigma), sigma * sigma + q * q / 12, 1e-9);
  }
}

TEST(RangeErrorModel, ClosedFormsMatchMonteCarloOfNoiseIntoTruncatingQuantizer) {
  // Independent truth: draw n ~ N(0, σ²), truncate r' + n, average (2.1)–(2.5).
  Rng rng(11);
  const double q = 0.05, sigma = 0.017;  // the thesis's SICK PLS values (fig. 2.3)
  for (double frac : {0.0, 0.2, 0.5, 0.8}) {
    const double r = 4.0 + frac * q;
    std::vector<double> err(40000);
    for (double& e : err) e = quantize(r + sigma * rng.normal(), q) - r;
    const Moments m = moments(err);
    const double var = quantizerErrorVariance(r, q, sigma);
    EXPECT_NEAR(m.mean, quantizerMeanError(r, q, sigma), 4.5 * std::sqrt(var / err.size())) << frac;
    EXPECT_NEAR(m.variance / var, 1.0, 0.03) << frac;
  }
}

TEST(RangeErrorModel, SinusoidalApproximationsFitWhenNoiseIsNotTooSmall) {
  // (2.6) and (2.7) for σ_n ≥ 0.3 q: residuals are below 0.5 % of q.
  for (auto [q, sigma] : {std::pair{0.05, 0.017}, std::pair{0.05, 0.015}, std::pair{0.01, 0.003}}) {
    const double b = quantizationBiasAmplitude(q, sigma);
    const QuantizerStdFit fit = quantizerStdFit(q, sigma);
    EXPECT_GT(b, 0.0);
    for (int i = 0; i < 50; ++i) {
      const double r = 2.0 + q * i / 50.0;
      const double phase = 2.0 * M_PI * (r - quantize(r, q)) / q;
      EXPECT_NEAR(quantizerMeanError(r, q, sigma), b * std::sin(phase) - q / 2, 0.005 * q);  // (2.6)
      EXPECT_NEAR(std::sqrt(quantizerErrorVariance(r, q, sigma)), fit.k1 * std::cos(phase) + fit.k2,
                  0.005 * q);  // (2.7)
      EXPECT_NEAR(quantizationBias(r, q, b), b * std::sin(phase), 1e-15);
    }
  }
}

TEST(RangeErrorModel, SystematicBiasSumsTheTermsOf28) {
  RangeErrorParams p;
  p.fixed_bias = 0.01;
  p.growth = 0.002;
  p.incidence = 0.004;
  p.max_incidence = deg2rad(80);
  EXPECT_NEAR(systematicRangeBias(p, 5.0, 2.0, deg2rad(30)), 0.01 + 0.002 * 3.0 + 0.004 * std::tan(deg2rad(30)), 1e-15);
  // β beyond max_incidence is clamped.
  EXPECT_NEAR(systematicRangeBias(p, 2.0, 2.0, deg2rad(89.9)), 0.01 + 0.004 * std::tan(deg2rad(80)), 1e-15);
}

// ---------------------------------------------------------------------------------------------
// The simulated laser

World wallAt(double x) {
  World w;
  w.addPolyline({{x, -20}, {x, 20}}, {Material::Wall}, false);
  return w;
}

LaserConfig singleBeam(double quantum, double sigma, bool compensate) {
  LaserConfig c;
  c.beams = 1;
  c.fov = 0.01;
  c.angle_min = 0.0;
  c.mount = Pose2();
  c.errors = RangeErrorParams{};
  c.errors.quantum = quantum;
  c.errors.noise_sigma = sigma;
  c.compensate_quantizer_offset = compensate;
  return c;
}

std::vector<double> errorsOfSingleBeam(const World& w, LaserSimulator& laser, double true_range, int n) {
  std::vector<double> err;
  for (int i = 0; i < n; ++i) {
    const LaserScan s = laser.scan(w, 0, [](double) { return Pose2(); });
    err.push_back(s.ranges[0] - true_range);
  }
  return err;
}

TEST(LaserSim, RangeErrorStatisticsMatchQuantizerClosedForms) {
  struct Case { double q, sigma; bool compensate; };
  for (const Case& c : {Case{0.05, 0.017, false}, Case{0.05, 0.017, true}, Case{0.01, 0.003, true}}) {
    LaserSimulator laser(singleBeam(c.q, c.sigma, c.compensate), 5);
    for (double frac : {0.1, 0.35, 0.6, 0.85}) {
      const double r = 3.0 + frac * c.q;
      const World w = wallAt(r);
      const Moments m = moments(errorsOfSingleBeam(w, laser, r, 12000));
      const double offset = c.compensate ? c.q / 2 : 0.0;
      const double var = quantizerErrorVariance(r, c.q, c.sigma);  // (2.5)
      EXPECT_NEAR(m.mean, quantizerMeanError(r, c.q, c.sigma) + offset,
                  4.5 * std::sqrt(var / 12000) + 1e-6)  // (2.4), float ranges
          << "q " << c.q << " frac " << frac;
      EXPECT_NEAR(m.variance / var, 1.0, 0.05) << "q " << c.q << " frac " << frac;
    }
  }
}

TEST(LaserSim, QuantizationBiasFollowsSinusoid26WithOffsetCompensated) {
  // With the q/2 compensation the mean error is b·sin(2π(r' − Q(r'))/q) alone: positive a
  // quarter step above a quantisation level, negative three quarters above.
  const double q = 0.01, sigma = 0.003;
  const double b = quantizationBiasAmplitude(q, sigma);
  ASSERT_GT(b, 5e-4);
  LaserSimulator laser(singleBeam(q, sigma, true), 9);
  for (double frac : {0.25, 0.75}) {
    const double r = 2.0 + frac * q;
    const std::vector<double> err = errorsOfSingleBeam(wallAt(r), laser, r, 12000);
    const Moments m = moments(err);
    const double standard_error = std::sqrt(m.variance / static_cast<double>(err.size()));
    const double approximation_residual = 0.005 * q;  // of (2.6), see RangeErrorModel tests
    EXPECT_NEAR(m.mean, quantizationBias(r, q, b), 4.5 * standard_error + approximation_residual) << frac;
    EXPECT_GT(m.mean * std::sin(2.0 * M_PI * frac), 0.7 * b) << frac;
  }
}

TEST(LaserSim, SystematicTermsOf28AppearExactlyWithoutNoise) {
  // A wall y = 2 seen by a 181-beam laser: r' = 2/sin φ, β = |π/2 − φ|, r_min = 2 (beam at 90°).
  LaserConfig c;
  c.mount = Pose2();
  c.angle_min = 0.0;
  c.fov = M_PI;
  c.errors = RangeErrorParams{};
  c.errors.fixed_bias = 0.01;
  c.errors.growth = 0.003;
  c.errors.incidence = 0.004;
  c.errors.max_incidence = deg2rad(80);
  c.compensate_quantizer_offset = false;
  World w;
  w.addPolyline({{-30, 2}, {30, 2}}, {Material::Wall}, false);
  LaserSimulator laser(c, 1);
  const LaserScan s = laser.scan(w, 0, [](double) { return Pose2(); });
  int checked = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    const double phi = s.bearing(i);
    if (phi < deg2rad(20) || phi > deg2rad(160)) continue;
    const double r_true = 2.0 / std::sin(phi);
    const double beta = std::abs(M_PI / 2 - phi);
    const double expected = r_true + 0.01 + 0.003 * (r_true - 2.0) + 0.004 * std::tan(std::min(beta, deg2rad(80)));
    EXPECT_NEAR(s.ranges[i], expected, 2e-6) << "beam " << i;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(LaserSim, PerScanBiasIsSharedByAllBeamsOfAScan) {
  LaserConfig c;
  c.mount = Pose2();
  c.errors = RangeErrorParams{};
  c.errors.scan_bias_sigma = 0.02;
  c.compensate_quantizer_offset = false;
  World w;
  w.addPolyline({{3, -30}, {3, 30}}, {Material::Wall}, false);
  LaserSimulator laser(c, 3);
  std::vector<double> biases;
  for (int k = 0; k < 3000; ++k) {
    const LaserScan s = laser.scan(w, 0, [](double) { return Pose2(); });
    const double bias0 = s.ranges[90] - 3.0;
    EXPECT_NEAR(s.ranges[60] - 3.0 / std::cos(s.bearing(60)), bias0, 1e-5);
    biases.push_back(bias0);
  }
  const Moments m = moments(biases);
  EXPECT_NEAR(m.mean, 0.0, 4.0 * 0.02 / std::sqrt(3000.0));
  EXPECT_NEAR(std::sqrt(m.variance), 0.02, 0.02 * 0.05);
}

TEST(LaserSim, TiltedPlaneLengthensReadingsBySecantOfElevation) {
  LaserConfig c;
  c.mount = Pose2();
  c.errors = RangeErrorParams{};
  c.compensate_quantizer_offset = false;
  c.tilt = deg2rad(3.0);
  c.tilt_axis = 0.0;  // tilt about the forward axis: beams to the sides rise and fall most
  World w;
  w.addPolyline({{-30, 2}, {30, 2}}, {Material::Wall}, false);
  LaserSimulator laser(c, 1);
  const LaserScan s = laser.scan(w, 0, [](double) { return Pose2(); });
  const size_t left = 180;  // bearing +90°: elevation = ε
  EXPECT_NEAR(s.bearing(left), M_PI / 2, 1e-12);
  EXPECT_NEAR(s.ranges[left], 2.0 / std::cos(deg2rad(3.0)), 1e-6);
  EXPECT_GT(s.ranges[left] - 2.0, 0.0025);  // ≈ r ε²/2 = 2.7 mm
}

TEST(LaserSim, NoReturnBeyondRangeMaxAndThroughGlass) {
  LaserConfig c;
  c.mount = Pose2();
  c.errors = RangeErrorParams{};
  c.compensate_quantizer_offset = false;
  World w;
  w.addPolyline({{2, -0.5}, {2, 0.5}}, {Material::Glass}, false);
  w.addPolyline({{-20, 9}, {20, 9}}, {Material::Wall}, false);  // beyond range_max 8.1
  LaserSimulator laser(c, 1);
  const LaserScan s = laser.scan(w, 0, [](double) { return Pose2(); });
  EXPECT_TRUE(validateScan(s).empty());
  for (size_t i = 0; i < s.size(); ++i) EXPECT_FALSE(s.valid(i)) << i;
}

TEST(LaserSim, EveryBeamIsMeasuredFromThePoseAtItsOwnTime) {
  // Robot turning on the spot at 1 rad/s inside the room, 1 ms between beams: the scan must be
  // the ray cast from each beam's own pose, and differ clearly from a scan taken at one pose.
  const World w = loadWorld(test::sourcePath("config/worlds/room.yaml"));
  LaserConfig c;
  c.errors = RangeErrorParams{};
  c.compensate_quantizer_offset = false;
  c.time_increment = 0.0005;
  LaserSimulator laser(c, 1);
  auto turning = [](double tau) { return Pose2(0.1, -0.2, 0.3 + 1.0 * tau); };
  const LaserScan s = laser.scan(w, 0, turning);
  double largest_distortion = 0.0;
  for (size_t i = 0; i < s.size(); ++i) {
    const double tau = static_cast<double>(i) * c.time_increment;
    const Pose2 at_beam = turning(tau) * c.mount, at_start = turning(0.0) * c.mount;
    const RayHit own = w.castRay(at_beam.translation(), at_beam.theta + s.bearing(i), c.range_max, Sensor::Laser);
    const RayHit frozen = w.castRay(at_start.translation(), at_start.theta + s.bearing(i), c.range_max, Sensor::Laser);
    ASSERT_TRUE(own.hit);
    EXPECT_NEAR(s.ranges[i], own.range, 1e-5) << i;
    largest_distortion = std::max(largest_distortion, std::abs(own.range - frozen.range));
  }
  EXPECT_GT(largest_distortion, 0.05);  // 90 ms of turning at 1 rad/s: ~5°
}

}  // namespace
}  // namespace polarslam
