// Gating, JCBB and ambiguity rejection on hand-built situations with a known right answer.
#include <gtest/gtest.h>

#include "slam/association.hpp"
#include "slam/feature_models.hpp"

namespace polarslam {
namespace {

/// A state with the robot at the origin (position std `robot_sigma`) and precisely known points.
EkfState pointMap(const std::vector<Vec2>& points, double robot_sigma, double point_sigma = 0.01) {
  EkfState s({}, Vec3(robot_sigma * robot_sigma, robot_sigma * robot_sigma, 1e-6).asDiagonal());
  for (size_t i = 0; i < points.size(); ++i) {
    Mat3 Gz = Mat3::Zero();
    Gz.topLeftCorner<2, 2>().setIdentity();
    // G_x = 0: the point is known in the map independently of the robot.
    s.addFeature(static_cast<int64_t>(i), MapFeatureKind::Point, Vec3(points[i].x(), points[i].y(), 0.0), Mat3::Zero(),
                 Gz, Mat3::Identity() * point_sigma * point_sigma);
  }
  return s;
}

/// Candidate lists of robot-frame point observations against every feature, gated.
std::vector<std::vector<AssociationCandidate>> candidatesFor(const EkfState& s, const std::vector<Vec2>& observed,
                                                             double meas_sigma, const AssociationParams& p) {
  std::vector<std::vector<AssociationCandidate>> out(observed.size());
  for (size_t i = 0; i < observed.size(); ++i) {
    for (size_t j = 0; j < s.features().size(); ++j) {
      const PointObservationModel m = observePoint(s.pose(), s.featureMean(static_cast<int>(j)).head<2>());
      LinearizedObservation lin;
      lin.feature = static_cast<int>(j);
      lin.dim = 2;
      lin.innovation.head<2>() = observed[i] - m.z;
      lin.H_x.topRows<2>() = m.H_x;
      lin.H_y.topLeftCorner<2, 2>() = m.H_y;
      lin.R.topLeftCorner<2, 2>() = Mat2::Identity() * meas_sigma * meas_sigma;
      const double d2 = mahalanobis2(s, lin);
      if (d2 <= chiSquaredGate(2, p.gate_probability)) out[i].push_back({lin, d2});
    }
    std::sort(out[i].begin(), out[i].end(), [](const auto& a, const auto& b) { return a.d2 < b.d2; });
  }
  return out;
}

int pairedFeature(const std::vector<std::vector<AssociationCandidate>>& c, const AssociationResult& r, size_t i) {
  return r.pairing[i] < 0 ? -1 : c[i][static_cast<size_t>(r.pairing[i])].lin.feature;
}

TEST(Association, PairsEachObservationWithItsOwnFeature) {
  const std::vector<Vec2> map = {{2, 0}, {0, 3}, {-2, -1}, {4, 4}, {1, -3}};
  const EkfState s = pointMap(map, 0.05);
  const Vec2 shift(0.03, -0.02);  // the robot is slightly off its estimate
  const std::vector<Vec2> observed = {map[3] - shift, map[0] - shift, map[4] - shift, map[1] - shift};
  const AssociationParams p;
  const auto c = candidatesFor(s, observed, 0.01, p);
  const AssociationResult r = associate(s, c, p);
  EXPECT_EQ(pairedFeature(c, r, 0), 3);
  EXPECT_EQ(pairedFeature(c, r, 1), 0);
  EXPECT_EQ(pairedFeature(c, r, 2), 4);
  EXPECT_EQ(pairedFeature(c, r, 3), 1);
  EXPECT_EQ(r.pairings, 4);
  EXPECT_LT(r.joint_nis, chiSquaredGate(8, 0.99));
}

TEST(Association, JointCompatibilityOverrulesTheNearestNeighbour) {
  // The robot is 0.4 m off its estimate (std 0.5 m). Observed from the true pose, point A looks
  // exactly like where the filter expects B = A − δ; only together with C does A fit.
  const Vec2 delta(0.4, 0.0);
  const Vec2 A(3.0, 0.0), B = A - delta, C(-1.0, 4.0);
  const EkfState s = pointMap({A, B, C}, 0.5);
  const std::vector<Vec2> observed = {A - delta, C - delta};
  const AssociationParams p;
  const auto c = candidatesFor(s, observed, 0.01, p);
  ASSERT_EQ(c[0].size(), 2u);
  ASSERT_EQ(c[0][0].lin.feature, 1);  // nearest neighbour alone would pick B
  const AssociationResult r = associate(s, c, p);
  EXPECT_EQ(pairedFeature(c, r, 0), 0);
  EXPECT_EQ(pairedFeature(c, r, 1), 2);
  EXPECT_FALSE(r.ambiguous[0]);
}

TEST(Association, RejectsAnObservationThatFitsTwoFeaturesEqually) {
  const EkfState s = pointMap({{3.0, 0.1}, {3.0, -0.1}}, 0.3);
  const std::vector<Vec2> observed = {{3.0, 0.0}};
  const AssociationParams p;
  const auto c = candidatesFor(s, observed, 0.01, p);
  ASSERT_EQ(c[0].size(), 2u);
  const AssociationResult r = associate(s, c, p);
  EXPECT_EQ(r.pairing[0], -1);
  EXPECT_TRUE(r.ambiguous[0]);
  EXPECT_EQ(r.pairings, 0);
}

TEST(Association, SwappedPairsThatFitEquallyAreBothRejected) {
  // Two observations and two features in a symmetric arrangement: either assignment fits.
  const EkfState s = pointMap({{3.0, 0.1}, {3.0, -0.1}}, 0.3);
  const std::vector<Vec2> observed = {{3.0, 0.01}, {3.0, -0.01}};
  const AssociationParams p;
  const auto c = candidatesFor(s, observed, 0.05, p);
  const AssociationResult r = associate(s, c, p);
  EXPECT_TRUE(r.ambiguous[0]);
  EXPECT_TRUE(r.ambiguous[1]);
  EXPECT_EQ(r.pairings, 0);
}

TEST(Association, AFeatureTakesAtMostOneObservation) {
  const EkfState s = pointMap({{2.0, 0.0}}, 0.05);
  const std::vector<Vec2> observed = {{2.0, 0.005}, {2.0, -0.004}};
  const AssociationParams p;
  const auto c = candidatesFor(s, observed, 0.01, p);
  const AssociationResult r = associate(s, c, p);
  EXPECT_EQ(r.pairings, 1);
  EXPECT_NE(r.pairing[0] >= 0, r.pairing[1] >= 0);
}

TEST(Association, ACutOffSearchStillReturnsAJointlyCompatibleHypothesis) {
  std::vector<Vec2> map;
  for (int i = 0; i < 8; ++i) map.push_back({1.0 + i, (i % 2 ? 1.0 : -1.0)});
  const EkfState s = pointMap(map, 0.05);
  std::vector<Vec2> observed;
  for (const Vec2& m : map) observed.push_back(m + Vec2(0.01, 0.0));
  AssociationParams p;
  p.max_nodes = 5;
  const auto c = candidatesFor(s, observed, 0.01, p);
  const AssociationResult r = associate(s, c, p);
  EXPECT_TRUE(r.budget_exhausted);
  EXPECT_GE(r.pairings, 1);
  std::vector<const LinearizedObservation*> chosen;
  int dim = 0;
  for (size_t i = 0; i < observed.size(); ++i)
    if (r.pairing[i] >= 0) {
      EXPECT_EQ(pairedFeature(c, r, i), static_cast<int>(i));
      chosen.push_back(&c[i][static_cast<size_t>(r.pairing[i])].lin);
      dim += 2;
    }
  EXPECT_LE(jointNis(s, chosen), chiSquaredGate(dim, p.gate_probability));
}

TEST(Association, NoCandidatesMeansNoPairings) {
  const EkfState s = pointMap({{2.0, 0.0}}, 0.05);
  const AssociationParams p;
  const auto c = candidatesFor(s, {{-5.0, 5.0}}, 0.01, p);
  ASSERT_TRUE(c[0].empty());
  const AssociationResult r = associate(s, c, p);
  EXPECT_EQ(r.pairing[0], -1);
  EXPECT_FALSE(r.ambiguous[0]);
}

}  // namespace
}  // namespace polarslam
