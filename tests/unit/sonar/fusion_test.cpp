// Laser–sonar fusion: the information-weighted average against its closed form and Monte Carlo,
// the χ² gate and the "same object" rules, laser-aided sonar selection on synthetic scans, and
// the stream logic of FeatureFusion (waiting, pairing by time, order, sonar-only grouping).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <numbers>
#include <random>

#include "sonar/feature_frames.hpp"
#include "sonar/feature_fusion.hpp"

namespace polarslam {
namespace {

LineFeature line(double alpha, double d, const Mat2& cov, FeatureSource source, Vec2 a = {-5, 0}, Vec2 b = {5, 0}) {
  LineFeature l;
  l.source = source;
  l.alpha = alpha;
  l.d = d;
  l.cov = cov;
  l.random_cov = cov;
  // Put the endpoints on the line: a.x, b.x are positions along it.
  const Vec2 foot = d * Vec2(std::cos(alpha), std::sin(alpha)), u(-std::sin(alpha), std::cos(alpha));
  l.endpoint_a = foot + a.x() * u;
  l.endpoint_b = foot + b.x() * u;
  return l;
}

LineFeature sonarPlane(double alpha, double d, const Mat2& cov) {
  LineFeature l = line(alpha, d, cov, FeatureSource::Sonar, {0, 0}, {0, 0});
  return l;
}

TEST(FusionMath, FusedLineIsTheInformationWeightedAverage) {
  const Mat2 P1 = (Mat2() << 4e-4, 1e-5, 1e-5, 1e-4).finished();
  const Mat2 P2 = (Mat2() << 1e-5, -2e-6, -2e-6, 1e-6).finished();
  // Angles straddling ±π: the average must not land near 0.
  const LineFeature a = line(std::numbers::pi - 0.01, 2.0, P1, FeatureSource::Laser);
  const LineFeature b = sonarPlane(-std::numbers::pi + 0.005, 2.02, P2);
  const LineFeature f = fuseLines(a, b);
  const Mat2 P = (P1.inverse() + P2.inverse()).inverse();
  const Vec2 z1(std::numbers::pi - 0.01, 2.0), z2(std::numbers::pi + 0.005, 2.02);  // z2 unwrapped next to z1
  const Vec2 z = P * (P1.inverse() * z1 + P2.inverse() * z2);
  EXPECT_NEAR(wrapAngle(f.alpha - z.x()), 0.0, 1e-12);
  EXPECT_NEAR(f.d, z.y(), 1e-12);
  EXPECT_TRUE(f.cov.isApprox(P, 1e-9));
  EXPECT_EQ(f.source, FeatureSource::Fused);
  EXPECT_TRUE(f.endpoint_a.isApprox(a.endpoint_a));
  // Fusion never loses information: P ≤ P1 and P ≤ P2.
  EXPECT_GE((P1 - f.cov).eigenvalues().real().minCoeff(), -1e-15);
  EXPECT_GE((P2 - f.cov).eigenvalues().real().minCoeff(), -1e-15);
}

TEST(FusionMath, FusedLineErrorMatchesItsCovarianceInMonteCarlo) {
  const Mat2 P1 = Vec2(deg2rad(0.5) * deg2rad(0.5), 1e-4).asDiagonal();
  const Mat2 P2 = (Mat2() << 3e-6, 1e-6, 1e-6, 2e-6).finished();
  const Eigen::LLT<Mat2> c1(P1), c2(P2);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> n(0, 1);
  const Vec2 truth(0.7, 3.0);
  double nees = 0.0;
  const int N = 20000;
  for (int i = 0; i < N; ++i) {
    const Vec2 e1 = c1.matrixL() * Vec2(n(rng), n(rng)), e2 = c2.matrixL() * Vec2(n(rng), n(rng));
    const LineFeature f = fuseLines(line(truth.x() + e1.x(), truth.y() + e1.y(), P1, FeatureSource::Laser),
                                    sonarPlane(truth.x() + e2.x(), truth.y() + e2.y(), P2));
    const Vec2 e(wrapAngle(f.alpha - truth.x()), f.d - truth.y());
    nees += e.dot(f.cov.inverse() * e);
  }
  EXPECT_NEAR(nees / N, 2.0, 0.06);  // mean of χ²₂; std of the mean ≈ 0.014
}

TEST(FusionMath, SonarCornerAddsApexInformationOnly) {
  CornerFeature laser;
  laser.x = 2.0;
  laser.y = 1.0;
  laser.gamma = 2.0;
  laser.cov << 1e-4, 2e-5, 1e-5,
               2e-5, 2e-4, -1e-5,
               1e-5, -1e-5, 3e-4;
  CornerFeature sonar;
  sonar.source = FeatureSource::Sonar;
  sonar.x = 2.01;
  sonar.y = 0.99;
  sonar.gamma = -2.5;  // placeholder: must not pull the laser's γ by its value
  sonar.cov = Vec3(1e-6, 1e-6, kUnknownAngleVariance).asDiagonal();
  const CornerFeature f = fuseCorners(laser, sonar);
  // Exact: information of the sonar on (x, y) only.
  Mat3 info = laser.cov.inverse();
  info.topLeftCorner<2, 2>() += Mat2::Identity() * 1e6;
  const Mat3 P = info.inverse();
  const Vec3 z = P * (laser.cov.inverse() * Vec3(2.0, 1.0, 2.0) + Vec3(2.01e6, 0.99e6, 0.0));
  EXPECT_TRUE(f.cov.isApprox(P, 1e-9));
  EXPECT_NEAR(f.x, z.x(), 1e-9);
  EXPECT_NEAR(f.y, z.y(), 1e-9);
  EXPECT_NEAR(f.gamma, z.z(), 1e-9);  // moves only through its correlation with the apex
  EXPECT_FALSE(cornerOrientationUnknown(f.cov));
  // The other order gives the same corner.
  const CornerFeature g = fuseCorners(sonar, laser);
  EXPECT_NEAR(g.x, f.x, 1e-9);
  EXPECT_NEAR(wrapAngle(g.gamma - f.gamma), 0.0, 1e-9);
}

TEST(FusionMath, GateAndSegmentDecideWhatIsTheSameObject) {
  const Mat2 laser_cov = Vec2(1e-4, 1e-4).asDiagonal(), sonar_cov = Vec2(1e-6, 1e-6).asDiagonal();
  FeatureSet laser;
  laser.frame = "base";
  laser.lines.push_back(line(std::numbers::pi / 2, 2.0, laser_cov, FeatureSource::Laser, {-1, 0}, {1, 0}));
  laser.lines.push_back(line(0.0, 3.0, laser_cov, FeatureSource::Laser, {-1, 0}, {1, 0}));
  FeatureSet sonar;
  sonar.lines.push_back(sonarPlane(std::numbers::pi / 2, 2.01, sonar_cov));   // same wall: fused
  sonar.lines.push_back(sonarPlane(0.0, 3.2, sonar_cov));                      // 20 σ away: alone
  LineFeature off_segment = sonarPlane(std::numbers::pi / 2 + 0.0, 2.0, sonar_cov);
  off_segment.endpoint_a = off_segment.endpoint_b = Vec2(-3.0, 2.0);           // foot beyond the segment
  sonar.lines.push_back(off_segment);
  FusionCounts counts;
  const FeatureSet out = fuseFeatureSets(laser, sonar, {}, &counts);
  EXPECT_EQ(counts.fused_lines, 1);
  EXPECT_EQ(counts.sonar_lines_alone, 2);
  ASSERT_EQ(out.lines.size(), 4u);
  EXPECT_EQ(out.lines[0].source, FeatureSource::Fused);
  EXPECT_NEAR(out.lines[0].d, 2.01, 1e-3);
  EXPECT_EQ(out.lines[1].source, FeatureSource::Laser);
}

TEST(FusionMath, ASonarPlaneMatchingTwoLaserLinesIsNotFused) {
  const Mat2 laser_cov = Vec2(1e-4, 1e-4).asDiagonal(), sonar_cov = Vec2(1e-6, 1e-6).asDiagonal();
  FeatureSet laser;
  laser.lines.push_back(line(0.0, 2.0, laser_cov, FeatureSource::Laser, {-1, 0}, {1, 0}));
  laser.lines.push_back(line(0.0, 2.005, laser_cov, FeatureSource::Laser, {-1.5, 0}, {0.5, 0}));
  FeatureSet sonar;
  sonar.lines.push_back(sonarPlane(0.0, 2.002, sonar_cov));
  FusionCounts counts;
  const FeatureSet out = fuseFeatureSets(laser, sonar, {}, &counts);
  EXPECT_EQ(counts.fused_lines, 0);
  EXPECT_EQ(counts.ambiguous, 1);
  EXPECT_EQ(out.lines.size(), 3u);
}

// ---- Laser-aided selection -----------------------------------------------------------------------

/// A 181-beam laser at the base origin looking along +x, seeing range(φ) for each beam (inf = no return).
template <typename RangeOf>
LaserScan syntheticScan(RangeOf range_of, double noise_sigma = 0.0, uint64_t seed = 0) {
  LaserScan s;
  s.angle_min = -std::numbers::pi / 2;
  s.angle_increment = deg2rad(1.0);
  s.range_max = 8.1;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, noise_sigma > 0 ? noise_sigma : 1.0);
  for (int i = 0; i < 181; ++i) {
    const double r = range_of(s.angle_min + i * s.angle_increment);
    s.ranges.push_back(static_cast<float>(std::isfinite(r) && noise_sigma > 0 ? r + n(rng) : r));
  }
  return normalizedScan(s);
}

/// Range to the wall y = 1 (a corridor wall 1 m to the left), with a jamb: between x = 0.7 and
/// 0.8 the wall stands `depth` closer (y = 1 − depth).
double wallWithJamb(double bearing, double depth) {
  if (bearing <= 0.05 || bearing >= std::numbers::pi - 0.05) return std::numeric_limits<double>::infinity();
  const double r = 1.0 / std::sin(bearing);
  const double x = r * std::cos(bearing);
  if (x > 0.7 && x < 0.8) return (1.0 - depth) / std::sin(bearing);
  return r;
}

SonarVerdict judge(const LaserScan& scan, const Vec2& p, const std::vector<LineFeature>& planes = {}) {
  LaserEvidence e;
  e.scan = &scan;
  e.sonar_planes = planes;
  return judgeSonarPoint(p, Mat2::Identity() * 1e-6, e, SonarSelectionParams{});
}

TEST(SonarSelection, VerdictsOnAWallWithAJamb) {
  const LaserScan scan = syntheticScan([](double b) { return wallWithJamb(b, 0.04); });
  EXPECT_EQ(judge(scan, {0.7, 0.96}), SonarVerdict::LaserBreak);         // the jamb's edge
  EXPECT_EQ(judge(scan, {0.1, 1.0}), SonarVerdict::LaserSurface);         // plain wall: unsupported point
  EXPECT_EQ(judge(scan, {0.3, 0.5}), SonarVerdict::FreeSpace);            // in front of the wall
  EXPECT_EQ(judge(scan, {0.3, 1.5}), SonarVerdict::BehindLaserSurface);   // behind it
  EXPECT_EQ(judge(scan, {-1.0, -2.0}), SonarVerdict::OutsideLaserView);   // behind the laser
  EXPECT_EQ(judge(scan, {-0.5, 1.0}), SonarVerdict::OutsideLaserView);    // beyond the 180° field of view
}

TEST(SonarSelection, GlassIsSeenByTheSonarNotTheLaser) {
  // Glass at y = 2 between x = −1 and 1: the laser looks through to a wall at y = 5.
  const LaserScan through = syntheticScan([](double b) {
    if (b <= 0.05 || b >= std::numbers::pi - 0.05) return std::numeric_limits<double>::infinity();
    return 5.0 / std::sin(b);
  });
  EXPECT_EQ(judge(through, {0.5, 2.0}), SonarVerdict::FreeSpace);
  EXPECT_EQ(judge(through, {0.5, 2.0}, {sonarPlane(std::numbers::pi / 2, 2.0, Mat2::Identity() * 1e-6)}),
            SonarVerdict::Glass);
  // Nothing behind the glass within range: no return at all.
  const LaserScan nothing = syntheticScan([](double) { return std::numeric_limits<double>::infinity(); });
  EXPECT_EQ(judge(nothing, {0.5, 2.0}), SonarVerdict::NoLaserReturn);
}

TEST(SonarSelection, StepTestFindsSmallJambsThroughNoiseAndRarelyFindsOneOnAPlainWall) {
  // Laser noise σ = 1.2 cm: a 4 cm jamb is 3σ deep, invisible to a jump detector, yet the bump
  // test over the readings next to the sonar point finds it.
  int found = 0, false_alarms = 0;
  const int trials = 300;
  for (int t = 0; t < trials; ++t) {
    const LaserScan jamb = syntheticScan([](double b) { return wallWithJamb(b, 0.04); }, 0.012, 100 + t);
    found += judge(jamb, {0.7, 0.96}) == SonarVerdict::LaserBreak;
    const LaserScan plain = syntheticScan([](double b) { return wallWithJamb(b, 0.0); }, 0.012, 5000 + t);
    false_alarms += judge(plain, {0.7, 1.0}) == SonarVerdict::LaserBreak;
  }
  EXPECT_GE(found, trials * 85 / 100);
  EXPECT_LE(false_alarms, trials * 5 / 100);
}

TEST(SonarSelection, SelectionDropsSpuriousReturnsAndUnsupportedPoints) {
  const LaserScan scan = syntheticScan([](double b) { return wallWithJamb(b, 0.05); });
  FeatureSet sonar;
  sonar.frame = "base";
  auto point = [](double x, double y) {
    PointFeature p;
    p.source = FeatureSource::Sonar;
    p.x = x;
    p.y = y;
    p.cov = Mat2::Identity() * 1e-6;
    return p;
  };
  sonar.points = {point(0.7, 0.95), point(0.1, 1.0), point(0.3, 0.5)};
  sonar.lines.push_back(sonarPlane(std::numbers::pi / 2, 1.0, Mat2::Identity() * 1e-6));
  sonar.lines.back().endpoint_a = sonar.lines.back().endpoint_b = Vec2(0.0, 1.0);
  LineFeature ghost = sonarPlane(std::numbers::pi / 2, 0.5, Mat2::Identity() * 1e-6);
  ghost.endpoint_a = ghost.endpoint_b = Vec2(0.0, 0.5);
  sonar.lines.push_back(ghost);
  LaserEvidence e;
  e.scan = &scan;
  SelectionCounts counts;
  const FeatureSet kept = selectSonarFeatures(sonar, e, {}, &counts);
  ASSERT_EQ(kept.points.size(), 1u);
  EXPECT_NEAR(kept.points[0].x, 0.7, 1e-12);
  ASSERT_EQ(kept.lines.size(), 1u);
  EXPECT_NEAR(kept.lines[0].d, 1.0, 1e-12);
  EXPECT_EQ(counts.spurious, 2);     // the free-space point and the ghost plane
  EXPECT_EQ(counts.unsupported, 1);  // the point on the plain wall
  EXPECT_EQ(kept.num_rejected, 3);
}

// ---- FeatureFusion streams -----------------------------------------------------------------------

SonarScan sonarScan(int64_t utime, int id, std::vector<SonarTarget> targets) {
  SonarScan s;
  s.utime = utime;
  s.sensor_id = id;
  s.sensor_pose = {0.0, 0.0, 0.0};
  s.targets = std::move(targets);
  return s;
}

SonarTarget planeAhead(double range) {
  SonarTarget t;
  t.kind = SonarKind::Plane;
  t.range = range;
  t.bearing = 0.0;
  t.cov = Vec2(1e-6, 3e-6).asDiagonal();
  return t;
}

FeatureSet laserFeatures(int64_t utime, double wall_distance) {
  FeatureSet f;
  f.utime = utime;
  f.frame = "laser";
  f.sensor_pose = {0.2, 0.0, 0.0};
  f.lines.push_back(line(0.0, wall_distance - 0.2, Vec2(1e-4, 1e-4).asDiagonal(), FeatureSource::Laser, {-1, 0}, {1, 0}));
  return f;
}

// A laser set waits sonar_wait_s of stream time, whatever has arrived meanwhile: live, the laser
// features reach the fusion after the sonar cycles of their own time, offline before them.
TEST(FeatureFusionStream, ALaserSetWaitsForTheSonarCycleOfItsTimeAndFusesWithIt) {
  FeatureFusionParams p;
  p.laser_aided_selection = false;
  FeatureFusion fusion(p);
  fusion.addSonar(sonarScan(900'000, 0, {planeAhead(3.0)}));  // an earlier cycle, alone
  fusion.addLaserFeatures(laserFeatures(1'000'000, 3.0));
  auto ready = fusion.takeReady();
  ASSERT_EQ(ready.size(), 1u);  // only the old sonar cycle
  EXPECT_EQ(ready[0].utime, 900'000);
  fusion.addSonar(sonarScan(1'000'000, 0, {planeAhead(3.001)}));
  EXPECT_TRUE(fusion.takeReady().empty()) << "released before sonar_wait_s of stream time";
  OdometryReading later;
  later.utime = 1'000'000 + static_cast<int64_t>(p.sonar_wait_s * 1e6);
  fusion.addOdometry(later);
  ready = fusion.takeReady();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].utime, 1'000'000);
  EXPECT_EQ(ready[0].frame, "base");
  ASSERT_EQ(ready[0].lines.size(), 1u);
  EXPECT_EQ(ready[0].lines[0].source, FeatureSource::Fused);
  EXPECT_NEAR(ready[0].lines[0].d, 3.001, 1e-4);
  EXPECT_EQ(fusion.stats().fusion.fused_lines, 1);
}

TEST(FeatureFusionStream, SonarCyclesFarFromAnyLaserScanGoAloneInTimeOrder) {
  FeatureFusionParams p;
  p.laser_aided_selection = false;
  FeatureFusion fusion(p);
  std::vector<FeatureSet> out;
  auto collect = [&] {
    for (auto& s : fusion.takeReady()) out.push_back(s);
  };
  fusion.addSonar(sonarScan(1'000'000, 0, {planeAhead(2.0)}));
  fusion.addSonar(sonarScan(1'100'000, 0, {planeAhead(2.0)}));
  fusion.addLaserFeatures(laserFeatures(1'300'000, 2.0));
  collect();
  fusion.addSonar(sonarScan(1'300'000, 0, {planeAhead(2.0)}));
  collect();
  fusion.addSonar(sonarScan(1'400'000, 0, {planeAhead(2.0)}));
  fusion.addSonar(sonarScan(2'000'000, 0, {planeAhead(2.0)}));
  collect();
  fusion.flush();
  collect();
  ASSERT_EQ(out.size(), 5u);
  for (size_t i = 1; i < out.size(); ++i) EXPECT_LT(out[i - 1].utime, out[i].utime);
  EXPECT_EQ(out[2].utime, 1'300'000);
  EXPECT_EQ(out[2].lines[0].source, FeatureSource::Fused);
  EXPECT_EQ(out[0].lines[0].source, FeatureSource::Sonar);
  // Too late to be emitted in order: counted, not emitted.
  EXPECT_FALSE(fusion.addSonar(sonarScan(1'500'000, 1, {planeAhead(2.0)})));
  EXPECT_EQ(fusion.stats().late, 1);
}

TEST(FeatureFusionStream, SonarCyclesAreMovedToTheLaserTimeWithOdometry) {
  FeatureFusionParams p;
  p.laser_aided_selection = false;
  FeatureFusion fusion(p);
  // Driving forward at 1 m/s along x: the sonar cycle 40 ms before the scan saw the wall 4 cm farther.
  for (int k = 0; k <= 10; ++k) {
    OdometryReading o;
    o.utime = 900'000 + k * 20'000;
    o.left_travel = o.right_travel = 0.02 * k;
    o.pose.x = 0.02 * k;
    fusion.addOdometry(o);
  }
  fusion.addSonar(sonarScan(960'000, 0, {planeAhead(3.04)}));
  fusion.addLaserFeatures(laserFeatures(1'000'000, 3.0));
  fusion.flush();
  const auto ready = fusion.takeReady();
  ASSERT_EQ(ready.size(), 1u);
  ASSERT_EQ(ready[0].lines.size(), 1u);
  EXPECT_EQ(ready[0].lines[0].source, FeatureSource::Fused);
  EXPECT_NEAR(ready[0].lines[0].d, 3.0, 1e-3);
  EXPECT_EQ(fusion.stats().uncompensated, 0);
}

TEST(FeatureFusionStream, SonarOnlyGroupsTheArraysOfOneCycle) {
  FeatureFusionParams p;
  p.use_laser = false;
  FeatureFusion fusion(p);
  fusion.addSonar(sonarScan(1'000'000, 0, {planeAhead(2.0)}));
  fusion.addSonar(sonarScan(1'000'000, 1, {planeAhead(3.0)}));
  EXPECT_TRUE(fusion.takeReady().empty());
  fusion.addSonar(sonarScan(1'100'000, 0, {planeAhead(2.0)}));
  auto ready = fusion.takeReady();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].lines.size(), 2u);
  EXPECT_FALSE(fusion.addLaserFeatures(laserFeatures(1'200'000, 2.0)));  // not in use
  fusion.flush();
  EXPECT_EQ(fusion.takeReady().size(), 1u);
}

TEST(FeatureFusionStream, LaserOnlyPassesSetsStraightThroughInTheBaseFrame) {
  FeatureFusionParams p;
  p.use_sonar = false;
  FeatureFusion fusion(p);
  fusion.addLaserFeatures(laserFeatures(1'000'000, 3.0));
  const auto ready = fusion.takeReady();
  ASSERT_EQ(ready.size(), 1u);
  EXPECT_EQ(ready[0].frame, "base");
  EXPECT_NEAR(ready[0].lines[0].d, 3.0, 1e-12);
  EXPECT_FALSE(fusion.addSonar(sonarScan(1'000'000, 0, {planeAhead(2.0)})));
}

}  // namespace
}  // namespace polarslam
