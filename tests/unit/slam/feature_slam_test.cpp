// FeatureSlam end to end on the synthetic room: consistency over Monte Carlo runs (NEES inside
// the χ² bounds), map accuracy, tentative features, line extents, scan anchors, and bad input.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <limits>

#include "eval/nees.hpp"
#include "slam/feature_slam.hpp"
#include "synthetic_world.hpp"

namespace polarslam {
namespace {

using testing::SyntheticNoise;
using testing::CircleRun;
using testing::SyntheticWorld;

struct RunResult {
  std::vector<double> nees;  ///< robot pose NEES at every 10th odometry step after the first second
  std::vector<Pose2> truth;
  FeatureSlam slam;
};

/// One run: odometry at 50 Hz, features at 10 Hz, for `seconds`.
RunResult runSynthetic(uint64_t seed, double seconds, const FeatureSlamParams& params = {}) {
  const SyntheticWorld world = testing::roomWorld();
  CircleRun run(world, SyntheticNoise{}, seed);
  RunResult result{{}, {}, FeatureSlam(params)};
  FeatureSlam& slam = result.slam;
  std::map<int64_t, Pose2> truth_at;
  slam.addOdometry(run.initialOdometry());
  truth_at[run.utime()] = run.truth();
  slam.addFeatures(run.observe());
  const int steps = static_cast<int>(seconds * 50);
  for (int k = 1; k <= steps; ++k) {
    slam.addOdometry(run.stepOdometry());
    truth_at[run.utime()] = run.truth();
    if (k % 5 == 0) slam.addFeatures(run.observe());
  }
  slam.flush();
  for (const PoseStamped& p : slam.takePoses()) {
    const auto it = truth_at.find(p.utime);
    if (it == truth_at.end()) continue;
    const int step = static_cast<int>((p.utime - CircleRun::kStart) / CircleRun::kOdometryPeriod);
    if (step < 50 || step % 10 != 0) continue;
    result.nees.push_back(poseNees(p.pose, p.cov, it->second));
    result.truth.push_back(it->second);
  }
  return result;
}

TEST(FeatureSlam, RobotPoseNeesStaysInsideChiSquaredBoundsOverMonteCarloRuns) {
  constexpr int kRuns = 24;
  std::vector<std::vector<double>> nees;
  for (int r = 0; r < kRuns; ++r) nees.push_back(runSynthetic(1000 + r, 36.0).nees);
  const NeesSummary s = summarizeNees(nees, 3, 0.95);
  EXPECT_GE(s.average, s.step_interval.lower) << "over-conservative";
  EXPECT_LE(s.average, s.step_interval.upper) << "over-confident";
  EXPECT_GE(s.fraction_steps_inside, 0.85) << "average NEES " << s.average;
}

TEST(FeatureSlam, BuildsTheRoomMapAndClosesTheLoop) {
  RunResult r = runSynthetic(7, 36.0);
  const FeatureMap map = r.slam.map();
  const SyntheticWorld world = testing::roomWorld();
  int lines = 0, corners = 0, points = 0;
  for (const MapFeature& f : map.features) {
    if (f.kind == MapFeatureKind::Line) {
      ++lines;
      double best = 1e9;
      for (const Vec2& l : world.lines) best = std::min(best, std::abs(f.params.y() - l.y()) + std::abs(wrapAngle(f.params.x() - l.x())));
      EXPECT_LT(best, 0.05);
      EXPECT_GE(f.params.y(), 0.0);
    } else if (f.kind == MapFeatureKind::Corner) {
      ++corners;
      double best = 1e9;
      for (const Vec3& c : world.corners) best = std::min(best, (f.params.head<2>() - c.head<2>()).norm());
      EXPECT_LT(best, 0.05);
    } else {
      ++points;
      double best = 1e9;
      for (const Vec2& p : world.points) best = std::min(best, (f.params.head<2>() - p).norm());
      EXPECT_LT(best, 0.05);
    }
  }
  // Every wall, corner and point within 6 m of the circle is mapped once (no duplicates).
  EXPECT_EQ(lines, 4);
  EXPECT_EQ(corners, 4);
  EXPECT_EQ(points, 7);
  const Pose2 end = map.robot.pose;
  EXPECT_LT((end.translation() - r.truth.back().translation()).norm(), 0.05);
  EXPECT_EQ(r.slam.stats().failed_updates, 0);
}

TEST(FeatureSlam, ASingleSpuriousObservationNeverEntersTheMap) {
  FeatureSlam slam;
  OdometryReading o;
  o.utime = 1'000'000;
  slam.addOdometry(o);
  FeatureSet set;
  set.utime = o.utime;
  PointFeature p;
  p.x = 2.0;
  p.cov = Mat2::Identity() * 1e-4;
  set.points.push_back(p);
  slam.addFeatures(set);
  for (int k = 1; k <= 25; ++k) {  // 2.5 s: past the 2 s tentative timeout
    o.utime += 100'000;
    slam.addOdometry(o);
    FeatureSet empty;
    empty.utime = o.utime;
    slam.addFeatures(empty);
  }
  slam.flush();
  EXPECT_TRUE(slam.map().features.empty());
  EXPECT_EQ(slam.stats().tentative_started, 1);
  EXPECT_EQ(slam.stats().tentative_expired, 1);
}

TEST(FeatureSlam, RepeatedObservationsPromoteAFeature) {
  FeatureSlamParams params;
  params.confirm_observations = 3;
  FeatureSlam slam(params);
  OdometryReading o;
  o.utime = 1'000'000;
  slam.addOdometry(o);
  for (int k = 0; k < 3; ++k) {
    FeatureSet set;
    set.utime = o.utime;
    PointFeature p;
    p.x = 2.0;
    p.y = 0.001 * k;
    p.cov = Mat2::Identity() * 1e-4;
    set.points.push_back(p);
    slam.addFeatures(set);
    o.utime += 100'000;
    slam.addOdometry(o);  // odometry past the set's time stamp lets it through
    EXPECT_EQ(slam.state().features().size(), k < 2 ? 0u : 1u) << k;
  }
  slam.flush();
  ASSERT_EQ(slam.map().features.size(), 1u);
  EXPECT_NEAR(slam.map().features[0].params.x(), 2.0, 0.01);
}

/// A wall y = 2 seen from a robot driving along x at 0.1 m per scan; scan k shows the wall
/// between x = k and x = k + 1 (map frame).
TEST(FeatureSlam, LineEndpointsGrowAsMoreOfTheWallIsSeen) {
  FeatureSlamParams params;
  params.confirm_observations = 1;
  FeatureSlam slam(params);
  OdometryReading o;
  o.utime = 1'000'000;
  slam.addOdometry(o);
  for (int k = 0; k < 5; ++k) {
    FeatureSet set;
    set.utime = o.utime;
    LineFeature l;
    l.alpha = std::numbers::pi / 2;
    l.d = 2.0;
    l.cov = Vec2(1e-5, 1e-4).asDiagonal();
    l.endpoint_a = {k - o.pose.x, 2.0};
    l.endpoint_b = {k + 1.0 - o.pose.x, 2.0};
    set.lines.push_back(l);
    slam.addFeatures(set);
    o.utime += 200'000;
    o.left_travel += 0.1;
    o.right_travel += 0.1;
    o.pose.x += 0.1;
    slam.addOdometry(o);
  }
  slam.flush();
  const FeatureMap map = slam.map();
  ASSERT_EQ(map.features.size(), 1u);
  const MapFeature& wall = map.features[0];
  const double x_min = std::min(wall.endpoint_a.x(), wall.endpoint_b.x());
  const double x_max = std::max(wall.endpoint_a.x(), wall.endpoint_b.x());
  EXPECT_NEAR(x_min, 0.0, 0.02);
  EXPECT_NEAR(x_max, 5.0, 0.02);
  EXPECT_NEAR(wall.endpoint_a.y(), 2.0, 0.01);
  EXPECT_NEAR(wall.endpoint_b.y(), 2.0, 0.01);
  EXPECT_EQ(wall.observations, 5);
}

/// A small target seen from one side, then at the same place from the opposite side (the far
/// face of a thin wall): another target, mapped on its own.
TEST(FeatureSlam, APointIsNotMatchedFromTheFarSide) {
  FeatureSlamParams params;
  params.confirm_observations = 1;
  FeatureSlam slam(params);
  OdometryReading o;
  o.utime = 1'000'000;
  slam.addOdometry(o);
  auto seePoint = [&](const Vec2& map_point) {
    FeatureSet set;
    set.utime = o.utime;
    PointFeature p;
    const Vec2 local = Pose2(o.pose.x, 0.0, 0.0).inverseTransform(map_point);
    p.x = local.x();
    p.y = local.y();
    p.cov = Mat2::Identity() * 1e-6;
    set.points.push_back(p);
    slam.addFeatures(set);
  };
  const Vec2 target(2.0, 0.5);
  seePoint(target);
  for (int k = 1; k <= 40; ++k) {  // drive 4 m along x, past the target
    o.utime += 100'000;
    o.left_travel = o.right_travel = o.pose.x = 0.1 * k;
    slam.addOdometry(o);
    if (k == 5) seePoint(target);  // still from behind-left: the same target
  }
  seePoint(target);  // now from ahead-right, 150° away from the first view
  o.utime += 100'000;
  slam.addOdometry(o);
  slam.flush();
  const FeatureMap map = slam.map();
  ASSERT_EQ(map.features.size(), 2u);
  EXPECT_EQ(map.features[0].observations, 2);
  EXPECT_EQ(map.features[1].observations, 1);
  EXPECT_EQ(slam.stats().paired, 1);
}

TEST(FeatureSlam, ScanAnchorsDescribeTheMapFromThePoseAtTheScan) {
  RunResult r = runSynthetic(3, 10.0);
  FeatureSlam& slam = r.slam;
  const ScanAnchors a = slam.anchorsNow(slam.filterTime());
  ASSERT_FALSE(a.anchors.empty());
  const FeatureMap map = slam.map();
  for (const AnchorObservation& o : a.anchors) {
    const auto f = std::find_if(map.features.begin(), map.features.end(), [&](const MapFeature& m) { return m.id == o.feature_id; });
    ASSERT_NE(f, map.features.end());
    ASSERT_EQ(f->kind, o.kind);
    if (o.kind == MapFeatureKind::Point) {
      EXPECT_TRUE(o.z.head<2>().isApprox(a.pose.pose.inverseTransform(f->params.head<2>()), 1e-9));
    } else if (o.kind == MapFeatureKind::Corner) {
      EXPECT_NEAR(o.z.y(), (f->params.head<2>() - a.pose.pose.translation()).norm(), 1e-9);
    } else {
      EXPECT_NEAR(o.z.y(), observeLine(a.pose.pose, f->params.head<2>()).z.y(), 1e-9);
    }
    const int n = parameterCount(o.kind);
    const Eigen::MatrixXd cov = o.cov.topLeftCorner(n, n);
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(cov).info(), Eigen::Success);
  }
}

TEST(FeatureSlam, AnchorRequestsAreAnsweredInTimeOrder) {
  const SyntheticWorld world = testing::roomWorld();
  CircleRun run(world, SyntheticNoise{}, 5);
  FeatureSlam slam;
  slam.addOdometry(run.initialOdometry());
  std::vector<int64_t> requested;
  for (int k = 1; k <= 200; ++k) {
    slam.addOdometry(run.stepOdometry());
    if (k % 5 == 0) {
      requested.push_back(run.utime());
      slam.requestAnchors(run.utime());
      slam.addFeatures(run.observe());
    }
  }
  slam.flush();
  const auto anchors = slam.takeAnchors();
  ASSERT_EQ(anchors.size(), requested.size());
  for (size_t i = 0; i < anchors.size(); ++i) EXPECT_EQ(anchors[i].utime, requested[i]);
  EXPECT_FALSE(anchors.back().anchors.empty());
}

TEST(FeatureSlam, BadInputIsCountedAndNeverCrashes) {
  FeatureSlam slam;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  OdometryReading o;
  o.utime = 1'000'000;
  EXPECT_TRUE(slam.addOdometry(o).empty());
  OdometryReading bad = o;
  bad.pose.x = nan;
  bad.utime += 20'000;
  EXPECT_FALSE(slam.addOdometry(bad).empty());
  OdometryReading backwards = o;
  backwards.utime -= 1;
  EXPECT_FALSE(slam.addOdometry(backwards).empty());
  OdometryReading jump = o;
  jump.utime += 40'000;
  jump.left_travel = jump.right_travel = 1e7;  // far beyond max_translation
  EXPECT_TRUE(slam.addOdometry(jump).empty());  // accepted in time; refused by the motion model

  FeatureSet set;
  set.utime = jump.utime;
  LineFeature l;
  l.alpha = nan;
  l.d = 1.0;
  l.cov = Mat2::Identity() * 1e-4;
  set.lines.push_back(l);
  LineFeature negative_cov;
  negative_cov.alpha = 0.3;
  negative_cov.d = 2.0;
  negative_cov.cov = -Mat2::Identity();
  set.lines.push_back(negative_cov);
  CornerFeature c;
  c.x = 1.0;
  c.y = 1.0;
  c.cov = Mat3::Identity() * nan;
  set.corners.push_back(c);
  PointFeature p;
  p.x = std::numeric_limits<double>::infinity();
  p.cov = Mat2::Identity();
  set.points.push_back(p);
  PointFeature on_robot;  // a line through the robot is skipped, a point there is fine
  on_robot.cov = Mat2::Identity() * 1e-4;
  set.points.push_back(on_robot);
  EXPECT_TRUE(slam.addFeatures(set).empty());
  FeatureSet nan_pose;
  nan_pose.utime = jump.utime + 1;
  nan_pose.sensor_pose.theta = nan;
  EXPECT_FALSE(slam.addFeatures(nan_pose).empty());
  FeatureSet old;
  old.utime = 0;
  EXPECT_FALSE(slam.addFeatures(old).empty());
  slam.flush();
  const FeatureSlamStats& s = slam.stats();
  EXPECT_EQ(s.rejected_features, 4);
  EXPECT_GE(s.rejected_odometry, 3);
  EXPECT_EQ(s.rejected_sets, 2);
  EXPECT_TRUE(std::isfinite(slam.currentPose().pose.x));
  EXPECT_TRUE(slam.state().covariance().allFinite());
}

TEST(FeatureSlam, FeaturesBeforeAnyOdometryAreProcessedAtTheOrigin) {
  FeatureSlamParams params;
  params.confirm_observations = 1;
  FeatureSlam slam(params);
  FeatureSet set;
  set.utime = 5'000'000;
  PointFeature p;
  p.x = 1.0;
  p.y = 2.0;
  p.cov = Mat2::Identity() * 1e-4;
  set.points.push_back(p);
  slam.addFeatures(set);
  slam.flush();
  ASSERT_EQ(slam.map().features.size(), 1u);
  EXPECT_NEAR(slam.map().features[0].params.y(), 2.0, 1e-9);
}

}  // namespace
}  // namespace polarslam
