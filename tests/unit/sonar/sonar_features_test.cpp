// Sonar targets → base-frame features: values, and covariances against Monte Carlo samples of the
// target's own range/bearing errors and of the mount pose.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <numbers>
#include <random>

#include "sonar/feature_frames.hpp"
#include "sonar/sonar_features.hpp"
#include "sonar/sonar_selection.hpp"

namespace polarslam {
namespace {

constexpr int kSamples = 40000;

template <int N>
Eigen::Matrix<double, N, N> sampleCovariance(const std::vector<Eigen::Matrix<double, N, 1>>& xs) {
  Eigen::Matrix<double, N, 1> mean = Eigen::Matrix<double, N, 1>::Zero();
  for (const auto& x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  Eigen::Matrix<double, N, N> cov = Eigen::Matrix<double, N, N>::Zero();
  for (const auto& x : xs) cov += (x - mean) * (x - mean).transpose();
  return cov / static_cast<double>(xs.size() - 1);
}

/// Each entry within `tolerance` of the predicted one, relative to the diagonal scale.
template <int N>
void expectCovarianceNear(const Eigen::Matrix<double, N, N>& predicted, const Eigen::Matrix<double, N, N>& sampled,
                          double tolerance) {
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) {
      const double scale = std::sqrt(predicted(r, r) * predicted(c, c));
      EXPECT_NEAR(sampled(r, c) / scale, predicted(r, c) / scale, tolerance) << "entry " << r << "," << c;
    }
}

struct Sampler {
  std::mt19937_64 rng{99};
  std::normal_distribution<double> n{0.0, 1.0};
  SonarTarget jitter(const SonarTarget& t) {
    SonarTarget s = t;
    s.range += std::sqrt(t.cov(0, 0)) * n(rng);
    s.bearing += std::sqrt(t.cov(1, 1)) * n(rng);
    return s;
  }
  Pose2 jitter(const Pose2& p, const Vec3& sigma) {
    return {p.x + sigma.x() * n(rng), p.y + sigma.y() * n(rng), p.theta + sigma.z() * n(rng)};
  }
};

SonarTarget target(SonarKind kind, double range, double bearing, double range_sigma, double bearing_sigma) {
  SonarTarget t;
  t.kind = kind;
  t.range = range;
  t.bearing = bearing;
  t.cov = Vec2(range_sigma * range_sigma, bearing_sigma * bearing_sigma).asDiagonal();
  return t;
}

const Vec3 kMountSigma(0.005, 0.004, deg2rad(0.3));

Mat3 mountCov() { return kMountSigma.cwiseAbs2().asDiagonal(); }

TEST(SonarFeatures, PlaneIsTheLineAlongTheEchoNormalInTheBaseFrame) {
  const Pose2 mount(0.0, 0.2, std::numbers::pi / 2);  // left-looking array
  const SonarTarget t = target(SonarKind::Plane, 1.3, 0.1, 0.001, deg2rad(0.1));
  Mat2 cov;
  ASSERT_TRUE(sonarTargetCovariance(t, {}, cov));
  const LineFeature l = sonarPlaneLine(t, mount, cov, Mat3::Zero());
  // Normal direction π/2 + 0.1 in the base frame; the array sits 0.2 m along y from the base.
  EXPECT_NEAR(l.alpha, std::numbers::pi / 2 + 0.1, 1e-12);
  EXPECT_NEAR(l.d, 1.3 + 0.2 * std::sin(std::numbers::pi / 2 + 0.1), 1e-12);
  EXPECT_EQ(l.source, FeatureSource::Sonar);
  // The foot of the normal is stored as the (one-point) segment.
  const Vec2 foot = mount.transform(1.3 * Vec2(std::cos(0.1), std::sin(0.1)));
  EXPECT_TRUE(l.endpoint_a.isApprox(foot, 1e-12));
  EXPECT_NEAR(l.endpoint_a.x() * std::cos(l.alpha) + l.endpoint_a.y() * std::sin(l.alpha), l.d, 1e-12);
}

TEST(SonarFeatures, PlaneCovarianceMatchesMonteCarlo) {
  const Pose2 mount(0.25, -0.1, 0.4);
  const SonarTarget t = target(SonarKind::Plane, 2.5, 0.3, 0.01, deg2rad(2.0));
  Mat2 cov;
  ASSERT_TRUE(sonarTargetCovariance(t, {}, cov));
  const LineFeature predicted = sonarPlaneLine(t, mount, cov, mountCov());
  Sampler s;
  std::vector<Vec2> samples;
  for (int i = 0; i < kSamples; ++i) {
    const LineFeature l = sonarPlaneLine(s.jitter(t), s.jitter(mount, kMountSigma), cov, Mat3::Zero());
    samples.push_back({wrapAngle(l.alpha - predicted.alpha), l.d});
  }
  expectCovarianceNear<2>(predicted.cov, sampleCovariance<2>(samples), 0.03);
}

TEST(SonarFeatures, EdgePointCovarianceMatchesMonteCarlo) {
  const Pose2 mount(0.0, -0.2, -std::numbers::pi / 2);
  const SonarTarget t = target(SonarKind::Edge, 3.0, -0.4, 0.01, deg2rad(1.0));
  Mat2 cov;
  ASSERT_TRUE(sonarTargetCovariance(t, {}, cov));
  const PointFeature predicted = sonarEdgePoint(t, mount, cov, mountCov());
  EXPECT_TRUE(Vec2(predicted.x, predicted.y).isApprox(mount.transform(3.0 * Vec2(std::cos(-0.4), std::sin(-0.4)))));
  Sampler s;
  std::vector<Vec2> samples;
  for (int i = 0; i < kSamples; ++i) {
    const PointFeature p = sonarEdgePoint(s.jitter(t), s.jitter(mount, kMountSigma), cov, Mat3::Zero());
    samples.push_back({p.x, p.y});
  }
  expectCovarianceNear<2>(predicted.cov, sampleCovariance<2>(samples), 0.03);
}

TEST(SonarFeatures, CornerApexCovarianceMatchesMonteCarloAndItsOrientationIsUnknown) {
  const Pose2 mount(0.25, 0.0, 0.0);
  const SonarTarget t = target(SonarKind::Corner, 4.0, 0.2, 0.01, deg2rad(1.0));
  Mat2 cov;
  ASSERT_TRUE(sonarTargetCovariance(t, {}, cov));
  const CornerFeature predicted = sonarCornerFeature(t, mount, cov, mountCov());
  EXPECT_FALSE(predicted.convex);
  EXPECT_TRUE(cornerOrientationUnknown(predicted.cov));
  EXPECT_GE(predicted.cov(2, 2), kUnknownAngleVariance);
  // γ placeholder: the direction from the apex back to the array.
  const Vec2 apex(predicted.x, predicted.y);
  const Vec2 back = mount.translation() - apex;
  EXPECT_NEAR(wrapAngle(predicted.gamma - std::atan2(back.y(), back.x())), 0.0, 1e-9);
  Sampler s;
  std::vector<Vec2> samples;
  for (int i = 0; i < kSamples; ++i) {
    const CornerFeature c = sonarCornerFeature(s.jitter(t), s.jitter(mount, kMountSigma), cov, Mat3::Zero());
    samples.push_back({c.x, c.y});
  }
  expectCovarianceNear<2>(Mat2(predicted.cov.topLeftCorner<2, 2>()), sampleCovariance<2>(samples), 0.03);
}

TEST(SonarFeatures, ScanConversionKeepsClassesAndCountsTheRest) {
  SonarScan scan;
  scan.utime = 42;
  scan.sensor_pose = {0.25, 0.0, 0.0};
  scan.range_max = 8.0;
  scan.targets = {target(SonarKind::Plane, 2.0, 0.0, 0.001, 0.002), target(SonarKind::Corner, 3.0, 0.2, 0.001, 0.002),
                  target(SonarKind::Edge, 1.5, -0.3, 0.001, 0.002), target(SonarKind::Unknown, 2.0, 0.1, 0.001, 0.002),
                  target(SonarKind::Edge, std::numeric_limits<double>::quiet_NaN(), 0.0, 0.001, 0.002),
                  target(SonarKind::Plane, 9.5, 0.0, 0.001, 0.002),    // beyond range_max
                  target(SonarKind::Plane, 0.01, 0.0, 0.001, 0.002)};  // closer than min_range
  SonarTarget weird = target(SonarKind::Edge, 2.0, 0.0, 0.001, 0.002);
  weird.kind = static_cast<SonarKind>(7);
  scan.targets.push_back(weird);
  SonarTarget bad_cov = target(SonarKind::Edge, 2.0, 0.0, 0.001, 0.002);
  bad_cov.cov(0, 0) = -1.0;
  scan.targets.push_back(bad_cov);
  SonarFeatureCounts counts;
  const FeatureSet set = sonarFeatures(scan, {}, &counts);
  EXPECT_EQ(set.frame, "base");
  EXPECT_EQ(set.utime, 42);
  EXPECT_EQ(set.lines.size(), 1u);
  EXPECT_EQ(set.corners.size(), 1u);
  EXPECT_EQ(set.points.size(), 1u);
  EXPECT_EQ(counts.unknown, 1);
  EXPECT_EQ(counts.invalid, 5);
  EXPECT_EQ(set.num_rejected, 6);
}

TEST(SonarFeatures, CovarianceFloorsApplyToOverConfidentTargets) {
  SonarTarget t = target(SonarKind::Edge, 2.0, 0.0, 1e-6, 1e-6);
  Mat2 cov;
  SonarFeatureParams p;
  ASSERT_TRUE(sonarTargetCovariance(t, p, cov));
  EXPECT_NEAR(cov(0, 0), p.range_sigma_floor * p.range_sigma_floor, 1e-15);
  EXPECT_NEAR(cov(1, 1), p.bearing_sigma_floor * p.bearing_sigma_floor, 1e-15);
}

TEST(SonarFeatures, BreakHintsAreBearingsInTheLaserFrame) {
  FeatureSet sonar;
  PointFeature edge;
  edge.x = 2.2;
  edge.y = 1.0;
  edge.cov = Mat2::Identity() * 1e-6;
  sonar.points.push_back(edge);
  CornerFeature corner;
  corner.x = 4.2;
  corner.y = -2.0;
  corner.cov = Vec3(1e-6, 1e-6, kUnknownAngleVariance).asDiagonal();
  sonar.corners.push_back(corner);
  const Pose2 laser(0.2, 0.0, 0.0);
  const auto hints = sonarBreakHints(sonar, laser);
  ASSERT_EQ(hints.size(), 2u);
  EXPECT_NEAR(hints[0].bearing, std::atan2(-2.0, 4.0), 1e-12);
  EXPECT_TRUE(hints[0].corner);
  EXPECT_NEAR(hints[1].bearing, std::atan2(1.0, 2.0), 1e-12);
  EXPECT_NEAR(hints[1].range, std::hypot(2.0, 1.0), 1e-12);
  EXPECT_NEAR(hints[1].bearing_sigma, 1e-3 / std::hypot(2.0, 1.0), 1e-9);
}

TEST(FeatureFrames, LaserFrameLinesMoveToTheBaseFrameWithTheirCovariance) {
  LineFeature l;
  l.alpha = 2.5;
  l.d = 0.1;  // close to the laser: in the base frame the line may pass behind the origin
  l.cov = Vec2(1e-4, 4e-4).asDiagonal();
  const Vec2 foot = l.d * Vec2(std::cos(l.alpha), std::sin(l.alpha)), along(-std::sin(l.alpha), std::cos(l.alpha));
  l.endpoint_a = foot - 0.5 * along;
  l.endpoint_b = foot + 0.7 * along;
  const Pose2 mount(0.3, 0.1, 0.2);
  const LineFeature b = transformLine(l, mount);
  EXPECT_GE(b.d, 0.0);
  for (const Vec2& e : {b.endpoint_a, b.endpoint_b})
    EXPECT_NEAR(e.x() * std::cos(b.alpha) + e.y() * std::sin(b.alpha), b.d, 1e-12);  // endpoints stay on the line
  EXPECT_NEAR((b.endpoint_b - b.endpoint_a).norm(), 1.2, 1e-12);
  // Monte Carlo of the transform of noisy lines.
  Sampler s;
  std::vector<Vec2> samples;
  const Eigen::LLT<Mat2> chol(l.cov);
  for (int i = 0; i < kSamples; ++i) {
    LineFeature noisy = l;
    const Vec2 e = chol.matrixL() * Vec2(s.n(s.rng), s.n(s.rng));
    noisy.alpha += e.x();
    noisy.d += e.y();
    const LineFeature t = transformLine(noisy, mount);
    samples.push_back({wrapAngle(t.alpha - b.alpha), t.d});
  }
  expectCovarianceNear<2>(b.cov, sampleCovariance<2>(samples), 0.03);
}

}  // namespace
}  // namespace polarslam
