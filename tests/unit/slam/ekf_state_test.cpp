// EkfState's sparse prediction, update and augmentation against the dense textbook formulas.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <random>

#include "slam/ekf_state.hpp"
#include "slam/feature_models.hpp"

namespace polarslam {
namespace {

Mat3 randomCovariance(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Mat3 A;
  for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = n(rng);
  return scale * (A * A.transpose() + 0.1 * Mat3::Identity());
}

/// A state with a few features of every kind and correlations between them.
EkfState exampleState(std::mt19937& rng) {
  EkfState s({1.0, 2.0, 0.4}, randomCovariance(rng, 0.01));
  const Mat3 R = randomCovariance(rng, 1e-3);
  auto add = [&](MapFeatureKind kind, const Vec3& z) {
    const Pose2 p = s.pose();
    if (kind == MapFeatureKind::Line) {
      const LineInitModel g = initLine(p, z.head<2>());
      Mat3 Gx = Mat3::Zero(), Gz = Mat3::Zero();
      Gx.topRows<2>() = g.G_x;
      Gz.topLeftCorner<2, 2>() = g.G_z;
      s.addFeature(static_cast<int64_t>(s.features().size()) + 1, kind, Vec3(g.y.x(), g.y.y(), 0), Gx, Gz, R);
    } else if (kind == MapFeatureKind::Point) {
      const PointInitModel g = initPoint(p, z.head<2>());
      Mat3 Gx = Mat3::Zero(), Gz = Mat3::Zero();
      Gx.topRows<2>() = g.G_x;
      Gz.topLeftCorner<2, 2>() = g.G_z;
      s.addFeature(static_cast<int64_t>(s.features().size()) + 1, kind, Vec3(g.y.x(), g.y.y(), 0), Gx, Gz, R);
    } else {
      const CornerInitModel g = initCorner(p, z);
      s.addFeature(static_cast<int64_t>(s.features().size()) + 1, kind, g.y, g.G_x, g.G_z, R);
    }
  };
  add(MapFeatureKind::Line, {0.3, 2.0, 0});
  add(MapFeatureKind::Point, {1.5, -0.7, 0});
  add(MapFeatureKind::Corner, {0.8, 3.0, 2.0});
  add(MapFeatureKind::Line, {-1.2, 1.1, 0});
  return s;
}

/// Dense H (m × n) of one linearised observation.
Eigen::MatrixXd denseH(const EkfState& s, const LinearizedObservation& o) {
  const StateFeature& f = s.features()[static_cast<size_t>(o.feature)];
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(o.dim, s.dimension());
  H.leftCols(3) = o.H_x.topRows(o.dim);
  H.block(0, f.offset, o.dim, f.size()) = o.H_y.block(0, 0, o.dim, f.size());
  return H;
}

LinearizedObservation pointObservation(const EkfState& s, int feature, const Vec2& z, const Mat2& R) {
  const PointObservationModel m = observePoint(s.pose(), s.featureMean(feature).head<2>());
  LinearizedObservation o;
  o.feature = feature;
  o.dim = 2;
  o.innovation.head<2>() = z - m.z;
  o.H_x.topRows<2>() = m.H_x;
  o.H_y.topLeftCorner<2, 2>() = m.H_y;
  o.R.topLeftCorner<2, 2>() = R;
  return o;
}

LinearizedObservation cornerObservation(const EkfState& s, int feature, const Vec3& z, const Mat3& R) {
  const CornerObservationModel m = observeCorner(s.pose(), s.featureMean(feature));
  LinearizedObservation o;
  o.feature = feature;
  o.dim = 3;
  o.innovation = Vec3(wrapAngle(z.x() - m.z.x()), z.y() - m.z.y(), wrapAngle(z.z() - m.z.z()));
  o.H_x = m.H_x;
  o.H_y = m.H_y;
  o.R = R;
  return o;
}

TEST(EkfState, AddedFeatureCovarianceEqualsDenseAugmentation) {
  std::mt19937 rng(3);
  EkfState s({0.5, -1.0, 1.0}, randomCovariance(rng, 0.02));
  const Eigen::MatrixXd P0 = s.covariance();
  const Vec2 z(2.0, 0.5);
  const Mat3 R = randomCovariance(rng, 1e-3);
  const PointInitModel g = initPoint(s.pose(), z);
  Mat3 Gx = Mat3::Zero(), Gz = Mat3::Zero();
  Gx.topRows<2>() = g.G_x;
  Gz.topLeftCorner<2, 2>() = g.G_z;
  s.addFeature(7, MapFeatureKind::Point, Vec3(g.y.x(), g.y.y(), 0), Gx, Gz, R);
  // Dense: P' = J·blkdiag(P, R)·Jᵀ with J = [[I, 0], [G_x, G_z]].
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(5, 5), B = Eigen::MatrixXd::Zero(5, 5);
  J.topLeftCorner(3, 3).setIdentity();
  J.block(3, 0, 2, 3) = g.G_x;
  J.block(3, 3, 2, 2) = g.G_z;
  B.topLeftCorner(3, 3) = P0;
  B.bottomRightCorner(2, 2) = R.topLeftCorner<2, 2>();
  EXPECT_TRUE(Eigen::MatrixXd(s.covariance()).isApprox(J * B * J.transpose(), 1e-12));
  EXPECT_EQ(s.features().back().id, 7);
  EXPECT_EQ(s.dimension(), 5);
}

TEST(EkfState, ManyAdditionsKeepEarlierEntriesThroughStorageGrowth) {
  std::mt19937 rng(5);
  EkfState s({}, randomCovariance(rng, 0.01));
  for (int i = 0; i < 60; ++i) {
    const PointInitModel g = initPoint(s.pose(), Vec2(1.0 + i, 0.5 * i));
    Mat3 Gx = Mat3::Zero(), Gz = Mat3::Zero();
    Gx.topRows<2>() = g.G_x;
    Gz.topLeftCorner<2, 2>() = g.G_z;
    s.addFeature(i, MapFeatureKind::Point, Vec3(g.y.x(), g.y.y(), 0), Gx, Gz, Mat3::Identity() * 1e-4);
  }
  EXPECT_EQ(s.dimension(), 3 + 120);
  EXPECT_NEAR(s.featureMean(0).x(), 1.0, 1e-12);
  EXPECT_NEAR(s.featureMean(59).y(), 29.5, 1e-12);
  const Eigen::MatrixXd P = s.covariance();
  EXPECT_TRUE(P.isApprox(P.transpose()));
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success);
}

TEST(EkfState, PredictionEqualsDenseJacobianPropagation) {
  std::mt19937 rng(11);
  EkfState s = exampleState(rng);
  const Eigen::MatrixXd P0 = s.covariance();
  const Pose2 x0 = s.pose();
  OdometryMotion motion;
  motion.delta = {0.3, 0.02, 0.1};
  motion.cov = randomCovariance(rng, 1e-4);
  s.predict(motion);
  const int n = s.dimension();
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(n, n), G = Eigen::MatrixXd::Zero(n, 3);
  F.topLeftCorner(3, 3) = composeJacobianA(x0, motion.delta);
  G.topRows(3) = composeJacobianB(x0);
  EXPECT_TRUE(Eigen::MatrixXd(s.covariance()).isApprox(F * P0 * F.transpose() + G * motion.cov * G.transpose(), 1e-12));
  const Pose2 expected = x0 * motion.delta;
  EXPECT_NEAR(s.pose().x, expected.x, 1e-12);
  EXPECT_NEAR(s.pose().theta, expected.theta, 1e-12);
}

TEST(EkfState, BatchUpdateEqualsDenseKalmanFormulas) {
  std::mt19937 rng(13);
  EkfState s = exampleState(rng);
  const Eigen::VectorXd x0 = s.mean();
  const Eigen::MatrixXd P0 = s.covariance();
  std::vector<LinearizedObservation> obs = {
      pointObservation(s, 1, Vec2(1.52, -0.69), Mat2::Identity() * 4e-4),
      cornerObservation(s, 2, Vec3(0.81, 2.97, 2.05), Vec3(1e-4, 4e-4, 1e-3).asDiagonal().toDenseMatrix()),
  };
  ASSERT_TRUE(s.update(obs));
  Eigen::MatrixXd H(5, s.dimension());
  Eigen::VectorXd nu(5);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(5, 5);
  H << denseH(s, obs[0]), denseH(s, obs[1]);
  nu << obs[0].innovation.head<2>(), obs[1].innovation;
  R.topLeftCorner(2, 2) = obs[0].R.topLeftCorner<2, 2>();
  R.bottomRightCorner(3, 3) = obs[1].R;
  const Eigen::MatrixXd S = H * P0 * H.transpose() + R;
  const Eigen::MatrixXd K = P0 * H.transpose() * S.inverse();
  Eigen::VectorXd expected = x0 + K * nu;
  const Eigen::MatrixXd expected_P = P0 - K * S * K.transpose();
  Eigen::VectorXd got = s.mean();
  EXPECT_NEAR(wrapAngle(got(2) - expected(2)), 0.0, 1e-12);
  got(2) = expected(2);
  for (const StateFeature& f : s.features())
    if (f.kind == MapFeatureKind::Line) got(f.offset) = expected(f.offset) + wrapAngle(got(f.offset) - expected(f.offset));
  EXPECT_TRUE(got.isApprox(expected, 1e-10));
  EXPECT_TRUE(Eigen::MatrixXd(s.covariance()).isApprox(expected_P, 1e-10));
  EXPECT_TRUE(Eigen::MatrixXd(s.covariance()).isApprox(Eigen::MatrixXd(s.covariance()).transpose(), 1e-14));
}

TEST(EkfState, InnovationAndCrossCovarianceEqualDenseProducts) {
  std::mt19937 rng(17);
  EkfState s = exampleState(rng);
  // Robot noise after the features were added: their innovations now share the robot's error.
  OdometryMotion motion;
  motion.delta = {0.5, 0.1, 0.2};
  motion.cov = randomCovariance(rng, 1e-2);
  s.predict(motion);
  const auto a = pointObservation(s, 1, Vec2(1.0, 0.0), Mat2::Identity() * 1e-3);
  const auto b = cornerObservation(s, 2, Vec3(0.8, 3.0, 2.0), Mat3::Identity() * 1e-3);
  const Eigen::MatrixXd P = s.covariance();
  const Eigen::MatrixXd Ha = denseH(s, a), Hb = denseH(s, b);
  EXPECT_TRUE(Eigen::MatrixXd(s.innovationCovariance(a).topLeftCorner(2, 2))
                  .isApprox(Ha * P * Ha.transpose() + a.R.topLeftCorner(2, 2), 1e-12));
  EXPECT_TRUE(Eigen::MatrixXd(s.crossCovariance(a, b).topLeftCorner(2, 3)).isApprox(Ha * P * Hb.transpose(), 1e-12));
  EXPECT_GT((Ha * P * Hb.transpose()).norm(), 1e-3);  // a real correlation, not round-off
}

TEST(EkfState, UpdateRefusesAnIndefiniteInnovationCovariance) {
  std::mt19937 rng(19);
  EkfState s = exampleState(rng);
  const Eigen::VectorXd x0 = s.mean();
  auto o = pointObservation(s, 1, Vec2(1.0, 0.0), Mat2::Identity() * -10.0);
  EXPECT_FALSE(s.update({o}));
  EXPECT_TRUE(Eigen::VectorXd(s.mean()).isApprox(x0));
}

}  // namespace
}  // namespace polarslam
