// The scan matcher's vector kernels (scanmatch/vector_kernels.hpp): every instruction set gives
// the same bits, and the joint system's sums are those of a plain loop over the bearings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "scan_fixtures.hpp"
#include "scanmatch/match_sums.hpp"
#include "scanmatch/scan_matcher.hpp"

namespace polarslam {
namespace {

fixtures::ScanSpec noisyLaser() {
  fixtures::ScanSpec spec;
  spec.noise_sigma = 0.01;
  return spec;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

void expectSameBits(const MatchResult& a, const MatchResult& b, int pair) {
  EXPECT_EQ(a.status, b.status) << pair;
  EXPECT_EQ(a.iterations, b.iterations) << pair;
  EXPECT_EQ(a.valid_points, b.valid_points) << pair;
  EXPECT_TRUE(sameBits(a.pose.x, b.pose.x) && sameBits(a.pose.y, b.pose.y) && sameBits(a.pose.theta, b.pose.theta))
      << pair;
  EXPECT_TRUE(sameBits(a.error_index, b.error_index)) << pair;
  for (int k = 0; k < 9; ++k) EXPECT_TRUE(sameBits(a.cov.data()[k], b.cov.data()[k])) << pair << " cov " << k;
}

TEST(VectorKernels, EveryInstructionSetMatchesToTheBit) {
  if (!vectorKernelsAvailable(VectorKernels::Avx2)) GTEST_SKIP() << "this processor has no AVX2: only the baseline runs";
  const World office = fixtures::clutteredOffice();
  fixtures::Noise noise(77);
  fixtures::ScanSpec spec = noisyLaser();
  ScanMatcher baseline, avx2;
  baseline.useKernels(VectorKernels::Baseline);
  avx2.useKernels(VectorKernels::Avx2);
  for (int pair = 0; pair < 60; ++pair) {
    const Pose2 a = fixtures::randomPose(noise, -3.5, -2.5, 3.5, 2.5);
    const Pose2 motion = fixtures::randomError(noise, 0.3, deg2rad(10.0));
    // Odd beam counts too: the kernels' last, partial block of bearings.
    spec.beams = pair % 2 == 0 ? 181 : 179 + pair % 4;
    const PreparedScan ref = prepareScan(fixtures::simulateScan(office, a, spec, &noise), {});
    const PreparedScan cur = prepareScan(fixtures::simulateScan(office, a * motion, spec, &noise), {});
    const Pose2 guess = motion * fixtures::randomError(noise, 0.5, deg2rad(30.0));
    for (MatchMethod method : {MatchMethod::Psm, MatchMethod::PsmC, MatchMethod::Icp})
      expectSameBits(baseline.match(ref, cur, guess, method), avx2.match(ref, cur, guess, method), pair);
    Projection p, q;
    projectScan(*ref.geometry, cur, guess, p, VectorKernels::Baseline);
    projectScan(*ref.geometry, cur, guess, q, VectorKernels::Avx2);
    EXPECT_EQ(0, std::memcmp(p.range.data(), q.range.data(), p.range.size() * sizeof(float))) << pair;
    EXPECT_EQ(p.tag, q.tag) << pair;
  }
}

TEST(VectorKernels, PreparationArithmeticMatchesToTheBit) {
  if (!vectorKernelsAvailable(VectorKernels::Avx2)) GTEST_SKIP() << "this processor has no AVX2: only the baseline runs";
  const World office = fixtures::clutteredOffice();
  fixtures::Noise noise(3);
  fixtures::ScanSpec spec = noisyLaser();
  for (size_t beams : {181, 182, 183, 361}) {
    spec.beams = beams;
    const PreparedScan scan = prepareScan(fixtures::simulateScan(office, {0.4, -0.3, 0.2}, spec, &noise), {});
    const BeamGeometry& g = *scan.geometry;
    const size_t n = scan.size(), padded = (n + 3) / 4 * 4;
    std::vector<double> moment(n), denominator(n);
    for (size_t i = 0; i < n; ++i) {
      moment[i] = noise.normal(3.0);
      denominator[i] = noise.uniform() < 0.2 ? 0.0 : noise.uniform(1.0, 20.0);
    }
    std::vector<float> slopes[2] = {std::vector<float>(n), std::vector<float>(n)};
    std::vector<double> terms[2][6];
    for (int k = 0; k < 2; ++k) {
      const VectorKernels kernels = k == 0 ? VectorKernels::Baseline : VectorKernels::Avx2;
      detail::divideSlopes(moment.data(), denominator.data(), n, slopes[k].data(), kernels);
      for (auto& t : terms[k]) t.assign(padded, -1.0);
      detail::surfaceTerms({scan.slope.data(), scan.range.data(), scan.slope_variance.data(), g.cos_table.data(),
                            g.sin_table.data(), scan.flags.data(), n, g.angle_increment},
                           {terms[k][0].data(), terms[k][1].data(), terms[k][2].data(), terms[k][3].data(),
                            terms[k][4].data(), terms[k][5].data()},
                           kernels);
    }
    EXPECT_EQ(0, std::memcmp(slopes[0].data(), slopes[1].data(), n * sizeof(float))) << beams;
    for (size_t i = 0; i < n; ++i)
      EXPECT_EQ(std::isnan(slopes[0][i]), denominator[i] == 0.0) << beams << " " << i;
    for (int t = 0; t < 6; ++t)
      EXPECT_EQ(0, std::memcmp(terms[0][t].data(), terms[1][t].data(), n * sizeof(double))) << beams << " term " << t;
    // And they are what the scan was prepared with.
    EXPECT_EQ(0, std::memcmp(terms[0][0].data(), scan.surface.rho.data(), n * sizeof(double))) << beams;
    EXPECT_EQ(0, std::memcmp(terms[0][5].data(), scan.surface.beta_variance.data(), n * sizeof(double))) << beams;
  }
}

/// The joint system's sums as a plain loop (docs/algorithms.md §11.1), to compare with.
JointSums plainSums(const JointInputs& in, const Pose2& pose, double c, const JointLimits& limits) {
  JointSums s;
  for (size_t j = 0; j < in.size; ++j) {
    if (in.flags[j] | in.tag[j]) continue;
    const double r = in.projected[j];
    if (!(r > limits.min_range && r < limits.max_range)) continue;
    const double e = in.measured[j] - r;
    if (std::abs(e) < 0.5 * limits.max_error) {
      s.sum_abs_error += std::abs(e);
      ++s.in_index;
    }
    if (std::abs(e) >= limits.max_error || !(std::abs(in.rho[j]) <= limits.max_slope)) continue;
    const double h1 = in.normal_x[j], h2 = in.normal_y[j];
    const double h3 = pose.y * h1 - pose.x * h2 - in.rho_cos_beta[j] * r;
    const double en = e * in.cos_beta[j], w = c / (c + e * e);
    s.a11 += w * h1 * h1;
    s.a12 += w * h1 * h2;
    s.a13 += w * h1 * h3;
    s.a22 += w * h2 * h2;
    s.a23 += w * h2 * h3;
    s.a33 += w * h3 * h3;
    s.g1 += w * h1 * en;
    s.g2 += w * h2 * en;
    s.g3 += w * h3 * en;
    s.sum_w += w;
    s.sum_we2 += w * en * en;
    ++s.used;
    const double u1 = h2, u2 = -h1, u3 = pose.y * h2 + pose.x * h1 - in.cos_beta[j] * r;
    const double k = w * in.beta_variance[j];
    s.s11 += k * (u1 * u1 - h1 * h1);
    s.s12 += k * (u1 * u2 - h1 * h2);
    s.s13 += k * (u1 * u3 - h1 * h3);
    s.s23 += k * (u2 * u3 - h2 * h3);
    s.s33 += k * (u3 * u3 - h3 * h3);
  }
  return s;
}

TEST(VectorKernels, JointSumsAreThoseOfAPlainLoopWhateverTheInputs) {
  // Random inputs with every kind of bearing: flagged, occluded, out of range, no return (+inf),
  // gated residuals, unknown slopes (NaN), grazing ones; sizes with and without a partial block.
  fixtures::Noise noise(5);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const JointLimits limits{0.1, 10.0, 1.0, 3.0};
  for (size_t n : {0, 1, 3, 4, 5, 181, 182, 183, 361}) {
    std::vector<float> projected(n), measured(n);
    std::vector<uint8_t> tag(n), flags(n);
    std::vector<double> rho(n), cos_beta(n), normal_x(n), normal_y(n), rho_cos_beta(n), beta_variance(n);
    for (size_t j = 0; j < n; ++j) {
      const double u = noise.uniform();
      measured[j] = static_cast<float>(noise.uniform(0.05, 12.0));
      projected[j] = u < 0.05 ? static_cast<float>(inf) : static_cast<float>(measured[j] + noise.normal(u < 0.1 ? 1.5 : 0.05));
      flags[j] = noise.uniform() < 0.05;
      tag[j] = noise.uniform() < 0.05 ? kFlagOccluded : 0;
      rho[j] = noise.uniform() < 0.05 ? nan : noise.normal(2.0);
      cos_beta[j] = std::isnan(rho[j]) ? nan : 1.0 / std::sqrt(1.0 + rho[j] * rho[j]);
      const double bearing = noise.uniform(-1.5, 1.5);
      normal_x[j] = (std::cos(bearing) + rho[j] * std::sin(bearing)) * cos_beta[j];
      normal_y[j] = (std::sin(bearing) - rho[j] * std::cos(bearing)) * cos_beta[j];
      rho_cos_beta[j] = rho[j] * cos_beta[j];
      beta_variance[j] = std::isnan(rho[j]) ? nan : noise.uniform(0.0, 0.1);
    }
    const JointInputs in{projected.data(),    measured.data(),      tag.data(),   flags.data(),
                         rho.data(),          cos_beta.data(),      normal_x.data(), normal_y.data(),
                         rho_cos_beta.data(), beta_variance.data(), n};
    const Pose2 pose{0.3, -0.2, 0.1};
    const JointSums plain = plainSums(in, pose, 0.01, limits);
    for (VectorKernels kernels : {VectorKernels::Baseline, VectorKernels::Avx2}) {
      const JointSums v = sumJointSystem(in, pose, 0.01, limits, kernels);
      EXPECT_EQ(v.used, plain.used) << n;
      EXPECT_EQ(v.in_index, plain.in_index) << n;
      const double sums[][2] = {{v.a11, plain.a11}, {v.a12, plain.a12}, {v.a13, plain.a13}, {v.a22, plain.a22},
                                {v.a23, plain.a23}, {v.a33, plain.a33}, {v.g1, plain.g1},   {v.g2, plain.g2},
                                {v.g3, plain.g3},   {v.sum_w, plain.sum_w}, {v.sum_we2, plain.sum_we2},
                                {v.sum_abs_error, plain.sum_abs_error}};
      for (const auto& [got, want] : sums) {
        ASSERT_TRUE(std::isfinite(got)) << n;
        EXPECT_NEAR(got, want, 1e-12 * (1.0 + std::abs(want))) << n;
      }
      const JointSums slope = sumJointSystem(in, pose, 0.01, limits, kernels, JointTerms::SlopeNoise);
      EXPECT_EQ(slope.used, plain.used) << n;
      const double slope_sums[][2] = {{slope.s11, plain.s11}, {slope.s12, plain.s12}, {slope.s13, plain.s13},
                                      {slope.s23, plain.s23}, {slope.s33, plain.s33}};
      for (const auto& [got, want] : slope_sums) {
        ASSERT_TRUE(std::isfinite(got)) << n;
        EXPECT_NEAR(got, want, 1e-12 * (1.0 + std::abs(want))) << n;
      }
    }
    if (n >= 181) {
      EXPECT_GT(static_cast<size_t>(plain.used), n / 2) << n;
    }
  }
}

TEST(VectorKernels, ShiftCostSlopeFitAndMasksAreThoseOfPlainLoops) {
  fixtures::Noise noise(9);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t n : {0, 1, 7, 8, 9, 61, 181, 183}) {
    std::vector<float> p(n), pm(n), r(n), rm(n), slope(n), range(n);
    std::vector<uint8_t> tag(n);
    for (size_t i = 0; i < n; ++i) {
      pm[i] = noise.uniform() < 0.8 ? 1.0f : 0.0f;
      rm[i] = noise.uniform() < 0.8 ? 1.0f : 0.0f;
      p[i] = pm[i] * static_cast<float>(noise.uniform(0.1, 8.0));
      r[i] = rm[i] * static_cast<float>(p[i] + noise.normal(noise.uniform() < 0.2 ? 2.0 : 0.05));
      slope[i] = static_cast<float>(noise.uniform() < 0.1 ? nan : noise.normal(0.05));
      range[i] = static_cast<float>(noise.uniform() < 0.1 ? std::numeric_limits<double>::infinity() : noise.uniform(0.0, 12.0));
      tag[i] = noise.uniform() < 0.1 ? kFlagEmpty : 0;
    }
    float sum = 0.0f, pairs = 0.0f;
    double num = 0.0, den = 0.0;
    const double c = 0.49, max_error = 1.0;
    for (size_t i = 0; i < n; ++i) {
      sum += std::min(std::abs(p[i] - r[i]), 1.0f) * pm[i] * rm[i];
      pairs += pm[i] * rm[i];
      const double e = static_cast<double>(p[i]) - r[i];
      if (pm[i] == 0.0f || rm[i] == 0.0f || !std::isfinite(slope[i]) || std::abs(e) >= max_error) continue;
      const double w = c / (c + e * e);
      num += w * slope[i] * e;
      den += w * slope[i] * slope[i];
    }
    for (VectorKernels kernels : {VectorKernels::Baseline, VectorKernels::Avx2}) {
      const ShiftCostSums cost = sumShiftCost({p.data(), pm.data(), r.data(), rm.data(), n, 1.0f}, kernels);
      EXPECT_EQ(cost.pairs, pairs) << n;
      EXPECT_NEAR(cost.sum, sum, 1e-5f * (1.0f + sum)) << n;
      const SlopeFitSums fit = sumSlopeFit({p.data(), pm.data(), r.data(), rm.data(), slope.data(), n, max_error}, c, kernels);
      EXPECT_NEAR(fit.num, num, 1e-12 * (1.0 + std::abs(num))) << n;
      EXPECT_NEAR(fit.den, den, 1e-12 * (1.0 + den)) << n;
      std::vector<float> values(n, -1.0f), mask(n, -1.0f);
      maskSamples({range.data(), tag.data(), n, 0.1, 10.0}, values.data(), mask.data(), kernels);
      for (size_t i = 0; i < n; ++i) {
        const bool use = tag[i] == 0 && range[i] > 0.1 && range[i] < 10.0;
        EXPECT_EQ(mask[i], use ? 1.0f : 0.0f) << n << " " << i;
        EXPECT_EQ(values[i], use ? range[i] : 0.0f) << n << " " << i;
      }
    }
  }
}

}  // namespace
}  // namespace polarslam
