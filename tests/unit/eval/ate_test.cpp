#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "eval/ate.hpp"

namespace polarslam {
namespace {

constexpr int64_t kSecond = 1000000;

/// A figure-eight-like path sampled at 10 Hz, heading along the path.
std::vector<PoseStamped> groundTruth() {
  std::vector<PoseStamped> poses;
  for (int i = 0; i < 200; ++i) {
    const double t = 0.1 * i;
    PoseStamped p;
    p.utime = i * kSecond / 10;
    p.pose = Pose2(5.0 * std::sin(0.2 * t), 3.0 * std::sin(0.4 * t), wrapAngle(0.3 * t));
    poses.push_back(p);
  }
  return poses;
}

std::vector<PoseStamped> moved(const std::vector<PoseStamped>& poses, const Pose2& transform) {
  std::vector<PoseStamped> out = poses;
  for (PoseStamped& p : out) p.pose = transform * p.pose;
  return out;
}

TEST(Ate, InStartFrameMakesTheFirstPoseTheOriginAndKeepsTheRelativePoses) {
  EXPECT_TRUE(inStartFrame({}).empty());
  const std::vector<PoseStamped> world{{1, Pose2(2.0, 1.0, 0.5), Mat3::Zero()}, {2, Pose2(3.0, -1.0, -1.0), Mat3::Zero()}};
  const std::vector<PoseStamped> start = inStartFrame(world);
  ASSERT_EQ(start.size(), 2u);
  EXPECT_NEAR(start[0].pose.translation().norm(), 0.0, 1e-12);
  EXPECT_NEAR(start[0].pose.theta, 0.0, 1e-12);
  const Pose2 expected = between(world[0].pose, world[1].pose);
  EXPECT_NEAR((start[1].pose.translation() - expected.translation()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(start[1].pose.theta, expected.theta, 1e-12);
  EXPECT_EQ(start[1].utime, 2);
}

TEST(Ate, PureOffsetGivesRawErrorEqualToOffsetAndAlignedZero) {
  const std::vector<PoseStamped> truth = groundTruth();
  const AteResult r = evaluateAte(moved(truth, Pose2(0.3, -0.4, 0.0)), truth);
  EXPECT_EQ(r.matched, truth.size());
  EXPECT_EQ(r.unmatched, 0u);
  EXPECT_NEAR(r.raw_translation.rmse, 0.5, 1e-12);
  EXPECT_NEAR(r.raw_translation.mean, 0.5, 1e-12);
  EXPECT_NEAR(r.raw_translation.median, 0.5, 1e-12);
  EXPECT_NEAR(r.raw_translation.max, 0.5, 1e-12);
  EXPECT_NEAR(r.raw_rotation_deg.max, 0.0, 1e-9);
  EXPECT_NEAR(r.aligned_translation.rmse, 0.0, 1e-9);
  EXPECT_NEAR(r.aligned_translation.max, 0.0, 1e-9);
  EXPECT_NEAR(r.alignment.x, -0.3, 1e-9);
  EXPECT_NEAR(r.alignment.y, 0.4, 1e-9);
}

TEST(Ate, RigidOffsetWithRotationIsRemovedByAlignment) {
  const std::vector<PoseStamped> truth = groundTruth();
  const Pose2 offset(2.0, -1.0, 0.7);
  const AteResult r = evaluateAte(moved(truth, offset), truth);
  EXPECT_NEAR(r.raw_rotation_deg.mean, rad2deg(0.7), 1e-9);
  EXPECT_GT(r.raw_translation.rmse, 1.0);
  EXPECT_NEAR(r.aligned_translation.rmse, 0.0, 1e-9);
  EXPECT_NEAR(r.aligned_rotation_deg.max, 0.0, 1e-9);
  const Pose2 inverse = offset.inverse();
  EXPECT_NEAR(r.alignment.x, inverse.x, 1e-9);
  EXPECT_NEAR(r.alignment.y, inverse.y, 1e-9);
  EXPECT_NEAR(r.alignment.theta, inverse.theta, 1e-9);
}

TEST(Ate, AlignmentIsTheLeastSquaresOneUnderNoise) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<Vec2> source, target;
  const Pose2 truth_transform(-1.0, 0.5, -2.0);
  for (int i = 0; i < 500; ++i) {
    const Vec2 p(std::cos(0.05 * i) * i * 0.02, std::sin(0.03 * i) * 4.0);
    source.push_back(p);
    target.push_back(truth_transform.transform(p) + Vec2(noise(rng), noise(rng)));
  }
  const Pose2 T = alignRigid2d(source, target);
  auto cost = [&](const Pose2& transform) {
    double sum = 0.0;
    for (size_t i = 0; i < source.size(); ++i) sum += (target[i] - transform.transform(source[i])).squaredNorm();
    return sum;
  };
  EXPECT_NEAR(T.theta, truth_transform.theta, 0.01);
  const double best = cost(T);
  for (const Pose2& nudge : {Pose2(1e-4, 0, 0), Pose2(0, -1e-4, 0), Pose2(0, 0, 1e-4), Pose2(0, 0, -1e-4)})
    EXPECT_GT(cost(nudge * T), best);
}

TEST(Ate, GroundTruthIsInterpolatedBetweenSamples) {
  // Straight line at 1 m/s along x: interpolation is exact at any time in between.
  std::vector<PoseStamped> truth;
  for (int i = 0; i <= 10; ++i) {
    PoseStamped p;
    p.utime = i * kSecond / 10;
    p.pose = Pose2(0.1 * i, 0.0, 0.0);
    truth.push_back(p);
  }
  std::vector<PoseStamped> estimate;
  for (int i = 0; i < 10; ++i) {
    PoseStamped p;
    p.utime = i * kSecond / 10 + 37000;
    p.pose = Pose2(0.1 * i + 0.037, 0.0, 0.0);
    estimate.push_back(p);
  }
  PoseStamped far;
  far.utime = 2 * kSecond;  // 1 s after the last ground truth: unmatched
  estimate.push_back(far);
  const AteResult r = evaluateAte(estimate, truth);
  EXPECT_EQ(r.estimated, 11u);
  EXPECT_EQ(r.matched, 10u);
  EXPECT_EQ(r.unmatched, 1u);
  EXPECT_NEAR(r.raw_translation.max, 0.0, 1e-12);
}

TEST(Ate, HeadingIsInterpolatedAcrossPi) {
  PoseStamped a, b, e;
  a.utime = 0;
  a.pose = Pose2(0, 0, 3.1);
  b.utime = 100000;
  b.pose = Pose2(0, 0, -3.1);
  e.utime = 50000;
  e.pose = Pose2(0, 0, std::numbers::pi);
  const AteResult r = evaluateAte({e}, {a, b});
  ASSERT_EQ(r.matched, 1u);
  EXPECT_NEAR(r.raw_rotation_deg.max, 0.0, 1e-9);
}

TEST(Ate, NoOverlapGivesZeroMatchesNotACrash) {
  PoseStamped e;
  e.utime = 100 * kSecond;  // ground truth ends at 19.9 s
  const AteResult r = evaluateAte({e}, groundTruth());
  EXPECT_EQ(r.matched, 0u);
  EXPECT_EQ(r.unmatched, 1u);
  EXPECT_EQ(r.aligned_translation.count, 0u);
  EXPECT_EQ(evaluateAte({}, {}).matched, 0u);
}

}  // namespace
}  // namespace polarslam
