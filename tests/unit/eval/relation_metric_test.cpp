#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "eval/error_statistics.hpp"
#include "eval/relation_metric.hpp"

namespace polarslam {
namespace {

constexpr int64_t kUsPerSecond = 1000000;

PoseStamped at(double seconds, double x, double y, double theta) {
  PoseStamped p;
  p.utime = static_cast<int64_t>(std::llround(seconds * kUsPerSecond));
  p.pose = Pose2(x, y, theta);
  return p;
}

Relation relation(double t1, double t2, double x, double y, double yaw) {
  Relation r;
  r.t1 = static_cast<int64_t>(std::llround(t1 * kUsPerSecond));
  r.t2 = static_cast<int64_t>(std::llround(t2 * kUsPerSecond));
  r.x = x;
  r.y = y;
  r.yaw = yaw;
  return r;
}

TEST(ErrorStatistics, KnownValues) {
  const ErrorStatistics s = summarizeErrors({3.0, 1.0, 2.0, 4.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(summarizeErrors({5.0, 1.0, 9.0}).median, 5.0);
  const ErrorStatistics none = summarizeErrors({});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.mean));
}

TEST(RelationMetric, TranslationOnly) {
  const std::vector<PoseStamped> trajectory = {at(0, 0, 0, 0), at(1, 1, 0, 0), at(2, 2.1, 0, 0)};
  const RelationMetric m =
      evaluateRelations(trajectory, {relation(0, 1, 1, 0, 0), relation(1, 2, 1, 0, 0), relation(0, 2, 2, 0.3, 0)});
  ASSERT_EQ(m.evaluated, 3u);
  EXPECT_NEAR(m.errors[0].translation, 0.0, 1e-12);
  EXPECT_NEAR(m.errors[1].translation, 0.1, 1e-12);
  EXPECT_NEAR(m.errors[2].translation, std::hypot(0.1, 0.3), 1e-12);
  const double e2 = std::hypot(0.1, 0.3);
  EXPECT_NEAR(m.translation.mean, (0.1 + e2) / 3.0, 1e-12);
  EXPECT_NEAR(m.translation.min, 0.0, 1e-12);
  EXPECT_NEAR(m.translation.max, e2, 1e-12);
  const double mean = (0.1 + e2) / 3.0;
  EXPECT_NEAR(m.translation.std,
              std::sqrt((mean * mean + (0.1 - mean) * (0.1 - mean) + (e2 - mean) * (e2 - mean)) / 3.0), 1e-12);
  EXPECT_NEAR(m.translation_squared.mean, (0.01 + 0.1) / 3.0, 1e-12);
  EXPECT_NEAR(m.translation_squared.max, 0.1, 1e-12);
  EXPECT_NEAR(m.rotation_deg.max, 0.0, 1e-12);
}

TEST(RelationMetric, RotationOnly) {
  const std::vector<PoseStamped> trajectory = {at(0, 0, 0, 0), at(1, 0, 0, 0.1), at(2, 0, 0, 0.1)};
  const RelationMetric m = evaluateRelations(trajectory, {relation(0, 1, 0, 0, 0.15), relation(1, 2, 0, 0, -0.02)});
  ASSERT_EQ(m.evaluated, 2u);
  EXPECT_NEAR(m.errors[0].rotation_deg, rad2deg(0.05), 1e-9);
  EXPECT_NEAR(m.errors[1].rotation_deg, rad2deg(0.02), 1e-9);
  EXPECT_NEAR(m.rotation_deg.mean, rad2deg(0.035), 1e-9);
  EXPECT_NEAR(m.rotation_deg.std, rad2deg(0.015), 1e-9);
  EXPECT_NEAR(m.rotation_squared.mean, (std::pow(rad2deg(0.05), 2) + std::pow(rad2deg(0.02), 2)) / 2.0, 1e-9);
  EXPECT_NEAR(m.translation.max, 0.0, 1e-12);
}

TEST(RelationMetric, CombinedMotionIsComparedInTheFrameOfTheFirstPose) {
  // Robot facing +y: one metre forward is +1 in y in the world but (1, 0) in its own frame.
  const std::vector<PoseStamped> trajectory = {at(0, 1, 2, std::numbers::pi / 2),
                                               at(1, 1, 3, std::numbers::pi / 2 + 0.2)};
  const RelationMetric m = evaluateRelations(trajectory, {relation(0, 1, 0.9, 0.1, 0.25)});
  ASSERT_EQ(m.evaluated, 1u);
  EXPECT_NEAR(m.errors[0].estimated_motion.x, 1.0, 1e-12);
  EXPECT_NEAR(m.errors[0].estimated_motion.y, 0.0, 1e-12);
  EXPECT_NEAR(m.errors[0].translation, std::sqrt(0.02), 1e-12);
  EXPECT_NEAR(m.errors[0].rotation_deg, rad2deg(0.05), 1e-9);
}

TEST(RelationMetric, AnglesAreWrapped) {
  // Across ±π: θ goes 3.1 → −3.1, a turn of 2π − 6.2 ≈ 0.0832 rad.
  const double turn = 2.0 * std::numbers::pi - 6.2;
  const std::vector<PoseStamped> trajectory = {at(0, 0, 0, 3.1), at(1, 0, 0, -3.1), at(2, 0, 0, 3.1)};
  const RelationMetric m = evaluateRelations(
      trajectory, {relation(0, 1, 0, 0, turn - 2.0 * std::numbers::pi),  // same turn written unwrapped
                   relation(1, 2, 0, 0, std::numbers::pi)});             // −0.0832 vs π: error π − 0.0832
  ASSERT_EQ(m.evaluated, 2u);
  EXPECT_NEAR(m.errors[0].rotation_deg, 0.0, 1e-9);
  EXPECT_NEAR(m.errors[1].rotation_deg, rad2deg(std::numbers::pi - turn), 1e-9);
  const RelationMetric near_pi =
      evaluateRelations({at(0, 0, 0, 0), at(1, 0, 0, -3.14)}, {relation(0, 1, 0, 0, 3.14)});
  EXPECT_NEAR(near_pi.errors[0].rotation_deg, rad2deg(2.0 * std::numbers::pi - 6.28), 1e-9);
}

TEST(RelationMetric, UsesNearestPoseAndSkipsRelationsWithoutPoseWithinTolerance) {
  const std::vector<PoseStamped> trajectory = {at(0.0, 0, 0, 0), at(1.0, 1, 0, 0), at(1.2, 1.5, 0, 0),
                                               at(3.0, 3, 0, 0)};
  const std::vector<Relation> relations = {
      relation(0.05, 1.04, 1, 0, 0),  // nearest: 0.0 and 1.0 → error 0
      relation(0.0, 1.12, 1.5, 0, 0),  // nearest to 1.12 is 1.2 → error 0
      relation(0.0, 2.0, 2, 0, 0),    // no pose within 0.1 s of 2.0 → skipped
      relation(-0.5, 1.0, 1, 0, 0),   // none near −0.5 → skipped
      relation(2.9, 3.0, 0, 0, 0),    // exactly 0.1 s from 3.0 → used
  };
  const RelationMetric m = evaluateRelations(trajectory, relations);
  EXPECT_EQ(m.relations, 5u);
  EXPECT_EQ(m.evaluated, 3u);
  EXPECT_EQ(m.skipped_no_pose, 2u);
  ASSERT_EQ(m.errors.size(), 3u);
  EXPECT_EQ(m.errors[0].relation_index, 0u);
  EXPECT_EQ(m.errors[1].relation_index, 1u);
  EXPECT_EQ(m.errors[1].estimate_t2, 1200000);
  EXPECT_EQ(m.errors[2].relation_index, 4u);
  EXPECT_NEAR(m.translation.max, 0.0, 1e-12);
  EXPECT_EQ(m.translation.count, 3u);

  RelationMetricOptions strict;
  strict.max_time_difference_us = 30000;
  EXPECT_EQ(evaluateRelations(trajectory, relations, strict).evaluated, 0u);
}

TEST(RelationMetric, UnsortedTrajectoryGivesTheSameAnswer) {
  const std::vector<PoseStamped> sorted = {at(0, 0, 0, 0), at(1, 1, 0, 0), at(2, 2.1, 0, 0.1)};
  const std::vector<PoseStamped> shuffled = {sorted[2], sorted[0], sorted[1]};
  const std::vector<Relation> relations = {relation(0, 1, 1, 0, 0), relation(0, 2, 2, 0, 0)};
  const RelationMetric a = evaluateRelations(sorted, relations), b = evaluateRelations(shuffled, relations);
  EXPECT_DOUBLE_EQ(a.translation.mean, b.translation.mean);
  EXPECT_DOUBLE_EQ(a.rotation_deg.mean, b.rotation_deg.mean);
}

TEST(RelationMetric, NonPlanarRelationComponentsCountAsError) {
  Relation r = relation(0, 1, 1, 0, 0);
  r.z = 0.3;
  r.roll = 0.04;
  const RelationMetric m = evaluateRelations({at(0, 0, 0, 0), at(1, 1, 0, 0)}, {r});
  EXPECT_NEAR(m.errors[0].translation, 0.3, 1e-12);
  EXPECT_NEAR(m.errors[0].rotation_deg, rad2deg(0.04), 1e-9);
}

TEST(RelationMetric, RelationsFromGroundTruthChainAtTheSpacing) {
  std::vector<PoseStamped> truth;
  for (int i = 0; i <= 30; ++i) truth.push_back(at(0.1 * i, std::cos(0.1 * i), std::sin(0.1 * i), 0.1 * i));
  const std::vector<Relation> r = relationsFromGroundTruth(truth, kUsPerSecond);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].t1, 0);
  EXPECT_EQ(r[0].t2, kUsPerSecond);
  EXPECT_EQ(r[2].t2, 3 * kUsPerSecond);
  EXPECT_NEAR(r[1].yaw, 1.0, 1e-9);
  // The ground truth itself scores zero on its own relations.
  const RelationMetric m = evaluateRelations(truth, r);
  EXPECT_EQ(m.evaluated, 3u);
  EXPECT_NEAR(m.translation.max, 0.0, 1e-12);
}

/// The relation from `a` to `b` as a relations file states it, with `error` added to its x.
Relation between(const PoseStamped& a, const PoseStamped& b, double error = 0.0) {
  const Pose2 m = polarslam::between(a.pose, b.pose);
  Relation r = relation(1e-6 * static_cast<double>(a.utime), 1e-6 * static_cast<double>(b.utime), m.x + error, m.y, m.theta);
  return r;
}

TEST(RelationConsistency, RelationsOfOneTrajectoryCloseEveryTriangle) {
  const PoseStamped a = at(0, 0, 0, 0), b = at(1, 1, 0.5, 0.7), c = at(2, 0.2, 2, 2.5), d = at(3, -1, 1, -2.0);
  // Two triangles (a b c, a c d), one relation given backwards, and a relation in no triangle.
  const std::vector<Relation> relations{between(a, b), between(b, c), between(c, a), between(c, d), between(a, d),
                                        between(d, at(4, 5, 5, 0))};
  const RelationConsistency consistency = relationConsistency(relations);
  EXPECT_EQ(consistency.triangles, 2u);
  EXPECT_EQ(consistency.relations, (std::vector<size_t>{0, 1, 2, 3, 4}));
  EXPECT_NEAR(consistency.translation.max, 0.0, 1e-12);
  EXPECT_NEAR(consistency.rotation_deg.max, 0.0, 1e-9);
}

TEST(RelationConsistency, ARelationsOwnErrorShowsInItsTriangles) {
  const PoseStamped a = at(0, 0, 0, 0), b = at(1, 1, 0.5, 0.7), c = at(2, 0.2, 2, 2.5), d = at(3, -1, 1, -2.0);
  // b→c is 3 cm off along x of b's frame: the one triangle holding it says so; a c d stays closed.
  const std::vector<Relation> relations{between(a, b), between(b, c, 0.03), between(a, c), between(c, d), between(a, d)};
  const RelationConsistency consistency = relationConsistency(relations);
  ASSERT_EQ(consistency.triangles, 2u);
  EXPECT_NEAR(consistency.translation.max, 0.03, 1e-9);
  EXPECT_NEAR(consistency.translation.min, 0.0, 1e-9);
  EXPECT_NEAR(consistency.per_relation_translation, 0.015 / std::sqrt(3.0), 1e-9);
  // Without triangles there is nothing to compare.
  EXPECT_EQ(relationConsistency({between(a, b), between(b, c)}).triangles, 0u);
  EXPECT_EQ(relationConsistency({}).triangles, 0u);
}

}  // namespace
}  // namespace polarslam
