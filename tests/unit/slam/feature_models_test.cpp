// App. B models (docs/algorithms.md §17.8): every Jacobian against central differences of its own function,
// including both sides of the line flip; h and g inverse to each other.
#include <gtest/gtest.h>

#include <functional>
#include <numbers>
#include <random>

#include "slam/feature_models.hpp"

namespace polarslam {
namespace {

using Fn = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

/// Central differences; `angle_rows` marks output rows that are angles (differences wrapped).
Eigen::MatrixXd numericJacobian(const Fn& f, const Eigen::VectorXd& x, const std::vector<int>& angle_rows,
                                double step = 1e-6) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd J(f0.size(), x.size());
  for (int c = 0; c < x.size(); ++c) {
    Eigen::VectorXd plus = x, minus = x;
    plus(c) += step;
    minus(c) -= step;
    Eigen::VectorXd d = f(plus) - f(minus);
    for (int r : angle_rows) d(r) = wrapAngle(d(r));
    J.col(c) = d / (2.0 * step);
  }
  return J;
}

Eigen::VectorXd vec(const Vec2& v) { return Eigen::VectorXd(v); }
Eigen::VectorXd vec(const Vec3& v) { return Eigen::VectorXd(v); }

class FeatureModels : public ::testing::Test {
 protected:
  std::mt19937 rng{20240611};
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  Pose2 randomPose() { return {uniform(-5, 5), uniform(-5, 5), uniform(-3.1, 3.1)}; }
};

TEST_F(FeatureModels, LineObservationJacobiansMatchNumericOnBothSidesOfTheFlip) {
  int flipped = 0, unflipped = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Pose2 pose = randomPose();
    const Vec2 line(uniform(-3.1, 3.1), uniform(0.2, 8.0));
    const LineObservationModel m = observeLine(pose, line);
    if (std::abs(line.y() - pose.x * std::cos(line.x()) - pose.y * std::sin(line.x())) < 0.05) continue;  // at the flip
    (m.s < 0 ? flipped : unflipped)++;
    EXPECT_GE(m.z.y(), 0.0);
    const Fn h_of_pose = [&](const Eigen::VectorXd& p) { return vec(observeLine(Pose2(p(0), p(1), p(2)), line).z); };
    const Fn h_of_line = [&](const Eigen::VectorXd& y) { return vec(observeLine(pose, Vec2(y(0), y(1))).z); };
    EXPECT_TRUE(numericJacobian(h_of_pose, vec(pose.vec()), {0}).isApprox(Eigen::MatrixXd(m.H_x), 1e-6))
        << "s=" << m.s << "\n" << m.H_x;
    EXPECT_TRUE(numericJacobian(h_of_line, vec(line), {0}).isApprox(Eigen::MatrixXd(m.H_y), 1e-6)) << "s=" << m.s;
  }
  EXPECT_GT(flipped, 30);
  EXPECT_GT(unflipped, 30);
}

TEST_F(FeatureModels, LineInitialisationJacobiansMatchNumericOnBothSidesOfTheFlip) {
  int flipped = 0, unflipped = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Pose2 pose = randomPose();
    const Vec2 z(uniform(-3.1, 3.1), uniform(0.2, 8.0));
    const LineInitModel m = initLine(pose, z);
    if (m.y.y() < 0.05) continue;
    (m.s < 0 ? flipped : unflipped)++;
    EXPECT_GE(m.y.y(), 0.0);
    const Fn g_of_pose = [&](const Eigen::VectorXd& p) { return vec(initLine(Pose2(p(0), p(1), p(2)), z).y); };
    const Fn g_of_z = [&](const Eigen::VectorXd& v) { return vec(initLine(pose, Vec2(v(0), v(1))).y); };
    EXPECT_TRUE(numericJacobian(g_of_pose, vec(pose.vec()), {0}).isApprox(Eigen::MatrixXd(m.G_x), 1e-6))
        << "s=" << m.s << "\n" << m.G_x;
    EXPECT_TRUE(numericJacobian(g_of_z, vec(z), {0}).isApprox(Eigen::MatrixXd(m.G_z), 1e-6)) << "s=" << m.s;
  }
  EXPECT_GT(flipped, 30);
  EXPECT_GT(unflipped, 30);
}

TEST_F(FeatureModels, FlippedLineEntriesCarryTheSignOnlyWhereNotesSayTheyDo) {
  // Robot beyond a line x = 1 (α = 0, d = 1): the observation flips.
  const Pose2 pose(3.0, 0.5, 0.0);
  const LineObservationModel h = observeLine(pose, {0.0, 1.0});
  EXPECT_EQ(h.s, -1.0);
  EXPECT_NEAR(h.z.x(), std::numbers::pi, 1e-12);
  EXPECT_NEAR(h.z.y(), 2.0, 1e-12);
  EXPECT_NEAR(h.H_x(1, 0), 1.0, 1e-12);  // −s·cos α_m
  EXPECT_NEAR(h.H_y(1, 1), -1.0, 1e-12);  // s
  // g of that observation gives the map line back, and its G_x carries no s on cos/sin.
  const LineInitModel g = initLine(pose, h.z);
  EXPECT_NEAR(wrapAngle(g.y.x()), 0.0, 1e-12);
  EXPECT_NEAR(g.y.y(), 1.0, 1e-12);
  EXPECT_EQ(g.s, -1.0);
  EXPECT_NEAR(g.G_x(1, 0), 1.0, 1e-12);  // cos α_m, not s·cos α_m
}

TEST_F(FeatureModels, PointJacobiansMatchNumeric) {
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2 pose = randomPose();
    const Vec2 p(uniform(-8, 8), uniform(-8, 8));
    const PointObservationModel h = observePoint(pose, p);
    EXPECT_TRUE(numericJacobian([&](const Eigen::VectorXd& x) { return vec(observePoint(Pose2(x(0), x(1), x(2)), p).z); },
                                vec(pose.vec()), {})
                    .isApprox(Eigen::MatrixXd(h.H_x), 1e-6));
    EXPECT_TRUE(numericJacobian([&](const Eigen::VectorXd& y) { return vec(observePoint(pose, Vec2(y(0), y(1))).z); },
                                vec(p), {})
                    .isApprox(Eigen::MatrixXd(h.H_y), 1e-6));
    const PointInitModel g = initPoint(pose, h.z);
    EXPECT_TRUE(g.y.isApprox(p, 1e-9));
    EXPECT_TRUE(numericJacobian([&](const Eigen::VectorXd& x) { return vec(initPoint(Pose2(x(0), x(1), x(2)), h.z).y); },
                                vec(pose.vec()), {})
                    .isApprox(Eigen::MatrixXd(g.G_x), 1e-6));
    EXPECT_TRUE(numericJacobian([&](const Eigen::VectorXd& z) { return vec(initPoint(pose, Vec2(z(0), z(1))).y); },
                                vec(h.z), {})
                    .isApprox(Eigen::MatrixXd(g.G_z), 1e-6));
  }
}

TEST_F(FeatureModels, CornerJacobiansMatchNumeric) {
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2 pose = randomPose();
    const Vec3 c(uniform(-8, 8), uniform(-8, 8), uniform(-3.1, 3.1));
    if ((c.head<2>() - pose.translation()).norm() < 0.3) continue;
    const CornerObservationModel h = observeCorner(pose, c);
    const Fn h_of_pose = [&](const Eigen::VectorXd& x) { return vec(observeCorner(Pose2(x(0), x(1), x(2)), c).z); };
    const Fn h_of_corner = [&](const Eigen::VectorXd& y) { return vec(observeCorner(pose, Vec3(y(0), y(1), y(2))).z); };
    EXPECT_TRUE(numericJacobian(h_of_pose, vec(pose.vec()), {0, 2}).isApprox(Eigen::MatrixXd(h.H_x), 1e-6)) << h.H_x;
    EXPECT_TRUE(numericJacobian(h_of_corner, vec(c), {0, 2}).isApprox(Eigen::MatrixXd(h.H_y), 1e-6)) << h.H_y;
    const CornerInitModel g = initCorner(pose, h.z);
    EXPECT_TRUE(g.y.head<2>().isApprox(c.head<2>(), 1e-9));
    EXPECT_NEAR(wrapAngle(g.y.z() - c.z()), 0.0, 1e-9);
    const Fn g_of_pose = [&](const Eigen::VectorXd& x) { return vec(initCorner(Pose2(x(0), x(1), x(2)), h.z).y); };
    const Fn g_of_z = [&](const Eigen::VectorXd& z) { return vec(initCorner(pose, Vec3(z(0), z(1), z(2))).y); };
    EXPECT_TRUE(numericJacobian(g_of_pose, vec(pose.vec()), {2}).isApprox(Eigen::MatrixXd(g.G_x), 1e-6));
    EXPECT_TRUE(numericJacobian(g_of_z, vec(h.z), {2}).isApprox(Eigen::MatrixXd(g.G_z), 1e-6));
  }
}

TEST_F(FeatureModels, CornerObservationSecondRowIsTheNegatedErratum) {
  // Erratum 5 of docs/algorithms.md §17.8: ∂r_r/∂y_m is minus ∂r_r/∂x_v's position part.
  const CornerObservationModel h = observeCorner({1.0, 2.0, 0.3}, {4.0, 6.0, 1.0});
  EXPECT_NEAR(h.z.y(), 5.0, 1e-12);
  EXPECT_NEAR(h.H_y(1, 0), 3.0 / 5.0, 1e-12);
  EXPECT_NEAR(h.H_y(1, 1), 4.0 / 5.0, 1e-12);
  EXPECT_NEAR(h.H_x(1, 0), -3.0 / 5.0, 1e-12);
}

TEST_F(FeatureModels, CornerPolarConversionJacobianMatchesNumeric) {
  for (int trial = 0; trial < 100; ++trial) {
    const Vec3 c(uniform(-5, 5), uniform(-5, 5), uniform(-3, 3));
    const PolarCorner p = cornerToPolar(c);
    EXPECT_TRUE(numericJacobian([](const Eigen::VectorXd& v) { return vec(cornerToPolar(Vec3(v(0), v(1), v(2))).z); },
                                vec(c), {0})
                    .isApprox(Eigen::MatrixXd(p.J), 1e-6));
  }
  EXPECT_TRUE(cornerToPolar(Vec3::Zero()).J.isZero());
}

TEST_F(FeatureModels, ObservationDifferenceWrapsOnlyAngles) {
  const Vec3 a(3.1, 5.0, -3.1), b(-3.1, 1.0, 3.1);
  const Vec3 line = observationDifference(MapFeatureKind::Line, a, b);
  EXPECT_NEAR(line.x(), 6.2 - 2 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(line.y(), 4.0, 1e-12);
  const Vec3 corner = observationDifference(MapFeatureKind::Corner, a, b);
  EXPECT_NEAR(corner.z(), -6.2 + 2 * std::numbers::pi, 1e-12);
  const Vec3 point = observationDifference(MapFeatureKind::Point, a, b);
  EXPECT_NEAR(point.x(), 6.2, 1e-12);
}

}  // namespace
}  // namespace polarslam
