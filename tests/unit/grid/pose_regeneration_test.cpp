// Pose regeneration against known truth: a map, a true pose, anchors observed from it.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "grid/anchor_model.hpp"
#include "grid/pose_regeneration.hpp"

namespace polarslam {
namespace {

MapFeature line(int64_t id, double alpha, double d, double sigma_alpha = 0.005, double sigma_d = 0.005) {
  MapFeature f;
  f.id = id;
  f.kind = MapFeatureKind::Line;
  f.params = {alpha, d, 0.0};
  f.cov.topLeftCorner<2, 2>() = Vec2(sigma_alpha * sigma_alpha, sigma_d * sigma_d).asDiagonal();
  return f;
}
MapFeature point(int64_t id, double x, double y, double sigma = 0.01) {
  MapFeature f;
  f.id = id;
  f.kind = MapFeatureKind::Point;
  f.params = {x, y, 0.0};
  f.cov.topLeftCorner<2, 2>() = Mat2::Identity() * sigma * sigma;
  return f;
}
MapFeature corner(int64_t id, double x, double y, double gamma, double sigma = 0.01) {
  MapFeature f;
  f.id = id;
  f.kind = MapFeatureKind::Corner;
  f.params = {x, y, gamma};
  f.cov = Vec3(sigma * sigma, sigma * sigma, 0.01 * 0.01).asDiagonal();
  return f;
}

/// The observation a perfect sensor makes of `f` from `pose`, with covariance `cov`.
AnchorObservation observe(const MapFeature& f, const Pose2& pose, const Mat3& cov) {
  const AnchorPrediction p = predictAnchor(pose, f);
  EXPECT_TRUE(p.valid);
  AnchorObservation a;
  a.feature_id = f.id;
  a.kind = f.kind;
  a.z = p.z;
  a.cov = cov;
  return a;
}

Mat3 observationCov(MapFeatureKind kind) {
  if (kind == MapFeatureKind::Line) return Vec3(1e-4, 1e-4, 0).asDiagonal();
  if (kind == MapFeatureKind::Point) return Vec3(1e-4, 1e-4, 0).asDiagonal();
  return Vec3(1e-4, 1e-4, 1e-3).asDiagonal();
}

/// Finite-difference check of H_x and H_y for every feature kind, including flipped lines.
TEST(AnchorModel, JacobiansMatchFiniteDifferences) {
  const std::vector<Pose2> poses = {{0.3, -0.2, 0.4}, {2.0, 1.0, -2.5}, {-1.0, 3.0, 3.0}};
  const std::vector<MapFeature> features = {line(1, 0.3, 2.0), line(2, -2.0, 0.5), line(3, 2.8, 4.0),
                                            point(4, 1.5, 2.5), corner(5, -2.0, 1.0, 0.7), corner(6, 3.0, -1.0, -2.9)};
  const double h = 1e-6;
  for (const Pose2& pose : poses)
    for (const MapFeature& f : features) {
      const AnchorPrediction p = predictAnchor(pose, f);
      ASSERT_TRUE(p.valid);
      for (int j = 0; j < 3; ++j) {
        Vec3 dx = Vec3::Zero();
        dx(j) = h;
        const AnchorPrediction plus = predictAnchor(Pose2(pose.vec() + dx), f);
        const AnchorPrediction minus = predictAnchor(Pose2(pose.vec() - dx), f);
        const Vec3 numeric = anchorResidual(f.kind, plus.z, minus.z) / (2 * h);
        for (int i = 0; i < p.dims; ++i) EXPECT_NEAR(p.H_x(i, j), numeric(i), 1e-5) << "H_x " << i << j;
      }
      for (int j = 0; j < parameterCount(f.kind); ++j) {
        MapFeature fp = f, fm = f;
        fp.params(j) += h;
        fm.params(j) -= h;
        const Vec3 numeric = anchorResidual(f.kind, predictAnchor(pose, fp).z, predictAnchor(pose, fm).z) / (2 * h);
        for (int i = 0; i < p.dims; ++i) EXPECT_NEAR(p.H_y(i, j), numeric(i), 1e-5) << "H_y " << i << j;
      }
    }
}

TEST(AnchorModel, LineThroughTheRobotIsInvalid) {
  EXPECT_FALSE(predictAnchor({1.0, 0.0, 0.0}, line(1, 0.0, 1.02), 0.05).valid);
  EXPECT_TRUE(predictAnchor({1.0, 0.0, 0.0}, line(1, 0.0, 1.2), 0.05).valid);
}

struct Scenario {
  FeatureMap map;
  ScanAnchors anchors;
};

/// A map, and anchors seen from `truth` with a stored pose that is wrong by `stored_error`.
Scenario scenario(const Pose2& truth, const Pose2& stored_error, std::vector<MapFeature> features) {
  Scenario s;
  s.map.features = std::move(features);
  s.anchors.utime = 1000;
  s.anchors.pose.pose = truth * stored_error;
  for (const MapFeature& f : s.map.features) s.anchors.anchors.push_back(observe(f, truth, observationCov(f.kind)));
  return s;
}

std::vector<MapFeature> roomFeatures() {
  return {line(1, 0.0, 3.0), line(2, std::numbers::pi / 2, 2.0), line(3, std::numbers::pi, 1.5),
          corner(4, 3.0, 2.0, deg2rad(-135.0)), point(5, -1.0, -1.5)};
}

TEST(PoseRegeneration, RecoversTheTruePoseFromAShiftedStoredPose) {
  const Pose2 truth(0.4, -0.3, deg2rad(20.0));
  Scenario s = scenario(truth, Pose2(0.6, -0.4, deg2rad(12.0)), roomFeatures());
  const RegeneratedPose r = regeneratePose(s.anchors, indexFeatures(s.map));
  ASSERT_EQ(r.source, PoseSource::Regenerated);
  EXPECT_NEAR(r.pose.x, truth.x, 1e-6);
  EXPECT_NEAR(r.pose.y, truth.y, 1e-6);
  EXPECT_NEAR(wrapAngle(r.pose.theta - truth.theta), 0.0, 1e-7);
  EXPECT_EQ(r.anchors_used, 5);
  EXPECT_LT(r.chi2, 1e-8);
}

/// The map moved (as after a loop closure): the regenerated pose follows the map, so the scan
/// keeps its place relative to the features.
TEST(PoseRegeneration, FollowsARigidlyMovedMap) {
  const Pose2 truth(1.0, 0.5, deg2rad(-40.0));
  Scenario s = scenario(truth, Pose2(), roomFeatures());
  const Pose2 shift(0.7, -0.2, deg2rad(8.0));  // new map = shift ⊕ old map
  for (MapFeature& f : s.map.features) {
    if (f.kind == MapFeatureKind::Line) {
      const double alpha = f.params.x() + shift.theta;
      f.params = {alpha, f.params.y() + shift.x * std::cos(alpha) + shift.y * std::sin(alpha), 0.0};
    } else {
      const Vec2 p = shift.transform(f.params.head<2>());
      f.params = {p.x(), p.y(), wrapAngle(f.params.z() + shift.theta)};
    }
  }
  const RegeneratedPose r = regeneratePose(s.anchors, indexFeatures(s.map));
  ASSERT_EQ(r.source, PoseSource::Regenerated);
  const Pose2 expected = shift * truth;
  EXPECT_NEAR(r.pose.x, expected.x, 1e-6);
  EXPECT_NEAR(r.pose.y, expected.y, 1e-6);
  EXPECT_NEAR(wrapAngle(r.pose.theta - expected.theta), 0.0, 1e-7);
}

/// With noisy anchors the estimate scatters as its own covariance says (Monte Carlo).
TEST(PoseRegeneration, CovarianceMatchesTheScatterOfNoisyAnchors) {
  const Pose2 truth(0.2, 0.1, deg2rad(5.0));
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int runs = 400;
  double nees_sum = 0.0;
  for (int k = 0; k < runs; ++k) {
    Scenario s = scenario(truth, Pose2(0.2, 0.2, 0.1), roomFeatures());
    for (AnchorObservation& a : s.anchors.anchors) {
      const int d = parameterCount(a.kind);
      const Eigen::LLT<Mat3> llt(a.cov + Mat3::Identity() * 1e-12);
      Vec3 noise(unit(rng), unit(rng), unit(rng));
      if (d == 2) noise.z() = 0.0;
      a.z += Mat3(llt.matrixL()) * noise;
    }
    RegenerationOptions o;
    o.include_map_covariance = false;  // the map here is exact
    o.reject_outliers = false;
    const RegeneratedPose r = regeneratePose(s.anchors, indexFeatures(s.map), o);
    ASSERT_EQ(r.source, PoseSource::Regenerated);
    Vec3 e = r.pose.vec() - truth.vec();
    e.z() = wrapAngle(e.z());
    nees_sum += e.dot(r.cov.inverse() * e);
  }
  // Mean NEES of a consistent 3-DOF estimate is 3; 95 % band for 400 runs ≈ 3 ± 0.34.
  EXPECT_NEAR(nees_sum / runs, 3.0, 0.4);
}

TEST(PoseRegeneration, OneLineIsUnderConstrained) {
  Scenario s = scenario(Pose2(0.0, 0.0, 0.3), Pose2(0.1, 0.0, 0.0), {line(1, 0.0, 3.0)});
  const RegeneratedPose r = regeneratePose(s.anchors, indexFeatures(s.map));
  EXPECT_EQ(r.source, PoseSource::Stored);
  EXPECT_DOUBLE_EQ(r.pose.x, s.anchors.pose.pose.x);
}

TEST(PoseRegeneration, TwoParallelLinesAreUnderConstrained) {
  Scenario s = scenario(Pose2(0.0, 0.0, 0.3), Pose2(), {line(1, 0.0, 3.0), line(2, std::numbers::pi, 1.0)});
  EXPECT_EQ(regeneratePose(s.anchors, indexFeatures(s.map)).source, PoseSource::Stored);
}

TEST(PoseRegeneration, AFarCornerWithAnUncertainOrientationIsUnderConstrained) {
  // 3.5 m away, heading known to 1.8°: the lateral position is only known to ~11 cm.
  Scenario s = scenario(Pose2(0.5, 0.5, 0.2), Pose2(), {corner(1, 3.5, 2.2, 2.5)});
  EXPECT_EQ(regeneratePose(s.anchors, indexFeatures(s.map)).source, PoseSource::Stored);
}

TEST(PoseRegeneration, TwoCrossingLinesOrOneCornerSuffice) {
  const Pose2 truth(0.5, 0.5, 0.2);
  Scenario lines = scenario(truth, Pose2(0.1, 0.1, 0.02), {line(1, 0.0, 3.0), line(2, 1.2, 2.0)});
  EXPECT_EQ(regeneratePose(lines.anchors, indexFeatures(lines.map)).source, PoseSource::Regenerated);
  // A corner 1.2 m away: its orientation (σ 1.8°) pins the heading well enough for position.
  Scenario one_corner = scenario(truth, Pose2(0.1, 0.1, 0.02), {corner(1, 1.5, 1.2, 2.5)});
  const RegeneratedPose r = regeneratePose(one_corner.anchors, indexFeatures(one_corner.map));
  EXPECT_EQ(r.source, PoseSource::Regenerated);
  EXPECT_NEAR(r.pose.x, truth.x, 1e-6);
}

TEST(PoseRegeneration, UnknownFeatureIdsAreIgnored) {
  Scenario s = scenario(Pose2(0.0, 0.0, 0.0), Pose2(), {line(1, 0.0, 3.0), line(2, 1.5, 2.0)});
  s.map.features.pop_back();  // feature 2 was deleted from the map since
  EXPECT_EQ(regeneratePose(s.anchors, indexFeatures(s.map)).source, PoseSource::Stored);
}

TEST(PoseRegeneration, AWrongAnchorIsRejected) {
  const Pose2 truth(0.3, 0.2, 0.1);
  std::vector<MapFeature> features = roomFeatures();
  features.push_back(point(6, 2.0, -1.0));
  features.push_back(line(7, -1.0, 2.5));
  Scenario s = scenario(truth, Pose2(0.2, 0.1, 0.05), features);
  s.anchors.anchors.back().z.y() += 0.5;  // a feature re-estimated 0.5 m away: must not drag the pose
  const RegeneratedPose r = regeneratePose(s.anchors, indexFeatures(s.map));
  ASSERT_EQ(r.source, PoseSource::Regenerated);
  EXPECT_EQ(r.anchors_rejected, 1);
  EXPECT_NEAR(r.pose.x, truth.x, 1e-6);
  EXPECT_NEAR(r.pose.y, truth.y, 1e-6);
}

/// An under-constrained scan between two regenerated ones takes its nearest neighbour's
/// correction, and is flagged Chained.
TEST(PoseRegeneration, UnderConstrainedScansAreChainedAndFlagged) {
  const std::vector<MapFeature> features = roomFeatures();
  FeatureMap map;
  map.features = features;
  const Pose2 correction(0.3, -0.1, 0.05);  // stored poses are all off by the same transform
  std::vector<ScanAnchors> scans;
  for (int k = 0; k < 3; ++k) {
    const Pose2 truth(0.1 * k, 0.0, 0.1 * k);
    Scenario s = scenario(truth, Pose2(), features);
    s.anchors.utime = 1000 * (k + 1);
    s.anchors.pose.pose = correction.inverse() * truth;
    if (k == 1) s.anchors.anchors.resize(1);  // only one line anchors the middle scan
    scans.push_back(s.anchors);
  }
  const std::vector<RegeneratedPose> poses = regeneratePoses(scans, map);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[0].source, PoseSource::Regenerated);
  EXPECT_EQ(poses[1].source, PoseSource::Chained);
  EXPECT_EQ(poses[2].source, PoseSource::Regenerated);
  const Pose2 truth1(0.1, 0.0, 0.1);
  EXPECT_NEAR(poses[1].pose.x, truth1.x, 1e-6);
  EXPECT_NEAR(poses[1].pose.y, truth1.y, 1e-6);
  EXPECT_NEAR(poses[1].pose.theta, truth1.theta, 1e-6);
  std::vector<const ScanAnchors*> pointers{&scans[0], &scans[1], &scans[2]};
  const RegenerationSummary summary = summarize(pointers, poses);
  EXPECT_EQ(summary.regenerated, 2);
  EXPECT_EQ(summary.chained, 1);
}

TEST(PoseRegeneration, NothingAnchoredKeepsTheStoredPoses) {
  FeatureMap empty;
  std::vector<ScanAnchors> scans(2);
  scans[0].pose.pose = Pose2(1, 2, 0.3);
  scans[1].pose.pose = Pose2(2, 2, 0.3);
  const auto poses = regeneratePoses(scans, empty);
  EXPECT_EQ(poses[0].source, PoseSource::Stored);
  EXPECT_EQ(poses[1].source, PoseSource::Stored);
  EXPECT_DOUBLE_EQ(poses[1].pose.x, 2.0);
}

}  // namespace
}  // namespace polarslam
