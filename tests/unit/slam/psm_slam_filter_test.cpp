// The delayed-state filter: equal to a plain dense EKF written here from the textbook, and
// consistent with the truth on small synthetic loops.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

#include "geometry/chi_squared.hpp"
#include "slam/psm_slam_filter.hpp"

namespace polarslam {
namespace {

Mat3 diag3(double a, double b, double c) { return Vec3(a, b, c).asDiagonal(); }

/// Textbook delayed-state EKF over [robot, keyframe 0, keyframe 1, ...], dense, no tricks.
class DenseEkf {
 public:
  DenseEkf(const Pose2& pose, const Mat3& cov) : x_(pose.vec()), P_(cov) {}

  void predict(const Pose2& u, const Mat3& Q) {
    const Pose2 r(x_.head<3>());
    const Eigen::Index n = x_.size();
    Eigen::MatrixXd F = Eigen::MatrixXd::Identity(n, n);
    F.topLeftCorner<3, 3>() = numericJacobian([&](const Vec3& v) { return (Pose2(v) * u).vec(); }, r.vec());
    const Mat3 G = numericJacobian([&](const Vec3& v) { return (r * Pose2(v)).vec(); }, u.vec());
    x_.head<3>() = (r * u).vec();
    P_ = F * P_ * F.transpose();
    P_.topLeftCorner<3, 3>() += G * Q * G.transpose();
  }

  void addKeyframe() {
    const Eigen::Index n = x_.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + 3, n);
    A.topRows(n).setIdentity();
    A.bottomRows<3>().leftCols<3>().setIdentity();
    x_ = A * x_;
    P_ = A * P_ * A.transpose();
  }

  bool update(size_t keyframe, const Pose2& z, const Mat3& R, double gate) {
    const Eigen::Index k = static_cast<Eigen::Index>(3 + 3 * keyframe), n = x_.size();
    auto h = [&](const Eigen::VectorXd& x) { return between(Pose2(x.segment<3>(k)), Pose2(x.head<3>())).vec(); };
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      Eigen::VectorXd plus = x_, minus = x_;
      plus(j) += 1e-6;
      minus(j) -= 1e-6;
      Vec3 d = h(plus) - h(minus);
      d.z() = wrapAngle(d.z());
      H.col(j) = d / 2e-6;
    }
    Vec3 nu = z.vec() - h(x_);
    nu.z() = wrapAngle(nu.z());
    const Mat3 S = H * P_ * H.transpose() + R;
    if (nu.dot(S.inverse() * nu) > gate) return false;
    const Eigen::MatrixXd K = P_ * H.transpose() * S.inverse();
    x_ += K * nu;
    P_ = (Eigen::MatrixXd::Identity(n, n) - K * H) * P_;
    P_ = 0.5 * (P_ + P_.transpose());
    return true;
  }

  const Eigen::VectorXd& x() const { return x_; }
  const Eigen::MatrixXd& P() const { return P_; }

 private:
  template <typename F>
  static Mat3 numericJacobian(F f, const Vec3& at) {
    Mat3 J;
    for (int j = 0; j < 3; ++j) {
      Vec3 plus = at, minus = at;
      plus(j) += 1e-6;
      minus(j) -= 1e-6;
      Vec3 d = f(plus) - f(minus);
      d.z() = wrapAngle(d.z());
      J.col(j) = d / 2e-6;
    }
    return J;
  }

  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
};

void expectStatesEqual(PsmSlamFilter& filter, const DenseEkf& dense, double tolerance) {
  const Eigen::VectorXd x = filter.stateMean();
  const Eigen::MatrixXd P = filter.stateCovariance();
  ASSERT_EQ(x.size(), dense.x().size());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double d = i % 3 == 2 ? wrapAngle(x(i) - dense.x()(i)) : x(i) - dense.x()(i);
    EXPECT_NEAR(d, 0.0, tolerance) << "state " << i;
  }
  EXPECT_LT((P - dense.P()).cwiseAbs().maxCoeff(), tolerance * std::max(1.0, dense.P().cwiseAbs().maxCoeff()));
}

TEST(PsmSlamFilter, RelativePoseJacobiansMatchFiniteDifferences) {
  const Pose2 k(1.0, -2.0, 0.7), r(3.0, 0.5, -2.5);
  const RelativePoseJacobians J = relativePoseJacobians(k, r);
  for (int j = 0; j < 3; ++j) {
    Vec3 dr = Vec3::Zero(), dk = Vec3::Zero();
    dr(j) = dk(j) = 1e-6;
    Vec3 fr = between(k, Pose2(r.vec() + dr)).vec() - between(k, Pose2(r.vec() - dr)).vec();
    Vec3 fk = between(Pose2(k.vec() + dk), r).vec() - between(Pose2(k.vec() - dk), r).vec();
    fr.z() = wrapAngle(fr.z());
    fk.z() = wrapAngle(fk.z());
    EXPECT_LT((J.robot.col(j) - fr / 2e-6).norm(), 1e-6);
    EXPECT_LT((J.keyframe.col(j) - fk / 2e-6).norm(), 1e-6);
  }
}

TEST(PsmSlamFilter, CompressedUpdatesEqualADenseEkf) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  PsmSlamFilter filter;
  filter.reset(Pose2(0.5, -0.2, 0.3), diag3(1e-3, 2e-3, 1e-4));
  DenseEkf dense(Pose2(0.5, -0.2, 0.3), diag3(1e-3, 2e-3, 1e-4));
  filter.addKeyframe(0);
  dense.addKeyframe();
  std::vector<int64_t> ids{0};
  for (int step = 0; step < 120; ++step) {
    const Pose2 u(0.2 + 0.05 * unit(rng), 0.02 * unit(rng), 0.1 * unit(rng));
    const Mat3 Q = diag3(4e-4, 1e-4, 3e-4);
    filter.predict(u, Q);
    dense.predict(u, Q);
    const double choice = uniform(rng);
    if (choice < 0.15) {
      filter.addKeyframe(static_cast<int64_t>(ids.size()));
      dense.addKeyframe();
      ids.push_back(static_cast<int64_t>(ids.size()));
    } else {
      // Mostly the active keyframe, sometimes an older one (a switch or a loop closure).
      const size_t k = choice < 0.8 ? static_cast<size_t>(filter.activeKeyframe())
                                    : static_cast<size_t>(uniform(rng) * static_cast<double>(ids.size()));
      const Pose2 truth_ish = filter.predictRelative(static_cast<int64_t>(k)).mean;
      const Pose2 z(truth_ish.x + 0.03 * unit(rng), truth_ish.y + 0.03 * unit(rng), truth_ish.theta + 0.01 * unit(rng));
      const Mat3 R = diag3(1e-3, 2e-3, 2e-4);
      const bool a = filter.update(static_cast<int64_t>(k), z, R, 1e9).accepted;
      const bool b = dense.update(k, z, R, 1e9);
      ASSERT_EQ(a, b);
    }
    if (step % 17 == 0) {
      // Reading a non-active keyframe must not need a flush to be right.
      for (size_t k = 0; k < ids.size(); ++k) {
        const Eigen::Index o = static_cast<Eigen::Index>(3 + 3 * k);
        const Pose2 p = filter.keyframePose(static_cast<int64_t>(k));
        EXPECT_NEAR(p.x, dense.x()(o), 1e-6);
        EXPECT_NEAR(p.y, dense.x()(o + 1), 1e-6);
        EXPECT_LT((filter.keyframeCovariance(static_cast<int64_t>(k)) - dense.P().block<3, 3>(o, o)).cwiseAbs().maxCoeff(),
                  1e-8);
      }
    }
  }
  expectStatesEqual(filter, dense, 1e-6);
  EXPECT_GT(filter.keyframeCount(), 5u);
  // The point of the compression: far fewer O(n²) passes than updates.
  EXPECT_LT(filter.flushCount(), 60u);
}

TEST(PsmSlamFilter, RelativePredictionMatchesTheDenseCovariance) {
  PsmSlamFilter filter;
  filter.reset(Pose2(), Mat3::Zero());
  DenseEkf dense(Pose2(), Mat3::Zero());
  for (int k = 0; k < 4; ++k) {
    filter.addKeyframe(k);
    dense.addKeyframe();
    const Pose2 u(1.0, 0.1, 0.4);
    filter.predict(u, diag3(1e-3, 1e-3, 1e-3));
    dense.predict(u, diag3(1e-3, 1e-3, 1e-3));
  }
  filter.update(3, Pose2(1.02, 0.09, 0.41), diag3(1e-4, 1e-4, 1e-4), 1e9);
  dense.update(3, Pose2(1.02, 0.09, 0.41), diag3(1e-4, 1e-4, 1e-4), 1e9);
  // Relative covariance of the robot seen from keyframe 1 (not active), by J·P·Jᵀ on the dense state.
  const RelativePosePrediction p = filter.predictRelative(1);
  const Eigen::Index n = dense.x().size();
  const Pose2 k1(dense.x().segment<3>(3 + 3)), r(dense.x().head<3>());
  const RelativePoseJacobians J = relativePoseJacobians(k1, r);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, n);
  H.leftCols<3>() = J.robot;
  H.middleCols<3>(6) = J.keyframe;
  const Mat3 expected = H * dense.P() * H.transpose();
  EXPECT_LT((p.cov - expected).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((p.mean.vec() - between(k1, r).vec()).norm(), 1e-9);
}

// boundRelative's spreads bound predictRelative's along the relative translation and in heading,
// for every keyframe, the active one and ones with pending (compressed) updates included.
TEST(PsmSlamFilter, RelativeBoundsHoldTheRelativeCovariance) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> step(-0.3, 1.0), turn(-0.6, 0.6), log_noise(-9.0, -3.0);
  PsmSlamFilter filter;
  filter.reset(Pose2(), diag3(1e-4, 2e-4, 1e-5));
  int checked = 0;
  for (int k = 0; k < 12; ++k) {
    filter.addKeyframe(k);
    for (int i = 0; i < 3; ++i) {
      filter.predict(Pose2(step(rng), 0.3 * step(rng), turn(rng)),
                     diag3(std::exp(log_noise(rng)), std::exp(log_noise(rng)), std::exp(log_noise(rng))));
      if (k > 2 && i == 1) {  // a match with an older keyframe leaves updates pending for the rest
        const int64_t old = k - 3;
        filter.update(old, filter.predictRelative(old).mean * Pose2(0.01, -0.02, 0.01), diag3(1e-4, 1e-4, 1e-5), 1e9);
      }
      for (int64_t id = 0; id <= k; ++id) {
        const RelativePosePrediction p = filter.predictRelative(id);
        const RelativePoseBound b = filter.boundRelative(id);
        EXPECT_EQ(b.mean.vec(), p.mean.vec()) << "keyframe " << id;
        const double distance = p.mean.translation().norm();
        if (distance > 1e-9) {
          const Vec2 u = p.mean.translation() / distance;
          EXPECT_LE(u.dot(p.cov.topLeftCorner<2, 2>() * u), b.position_sigma * b.position_sigma * (1.0 + 1e-9)) << "keyframe " << id;
        }
        EXPECT_LE(p.cov(2, 2), b.heading_sigma * b.heading_sigma * (1.0 + 1e-9)) << "keyframe " << id;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 200);
}

/// Drives around a square with noisy odometry; keyframes every few steps, matches to the
/// active keyframe drawn from the true relative pose; at the end a match with keyframe 0.
struct LoopOutcome {
  double nees_robot = 0.0;           ///< robot pose error² normalised by its covariance
  double end_error_before = 0.0;     ///< robot position error before the closure
  double end_error_after = 0.0;
  bool closure_accepted = false;
  bool wrong_closure_accepted = false;
};

LoopOutcome runSyntheticLoop(uint64_t seed, bool try_wrong_closure) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Mat3 Q = diag3(4e-4, 4e-4, 2.5e-4);      // odometry per 0.5 m step
  const Mat3 R = diag3(1e-4, 1e-4, 3e-5);        // scan match
  const Eigen::Matrix3d Lq = Q.llt().matrixL(), Lr = R.llt().matrixL();
  PsmSlamFilter filter;
  filter.reset(Pose2(), Mat3::Zero());
  Pose2 truth;
  std::vector<Pose2> keyframe_truth;
  filter.addKeyframe(0);
  keyframe_truth.push_back(truth);
  LoopOutcome out;
  const int per_side = 12;
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < per_side; ++k) {
      const Pose2 step(0.5, 0.0, k == per_side - 1 ? M_PI / 2 : 0.0);
      truth = truth * step;
      const Vec3 n = Lq * Vec3(unit(rng), unit(rng), unit(rng));
      filter.predict(Pose2(step.x + n.x(), step.y + n.y(), step.theta + n.z()), Q);
      // Match with the active keyframe only every other step: odometry must carry the rest.
      const int64_t active = filter.activeKeyframe();
      if (k % 2 == 0) {
        const Pose2 rel = between(keyframe_truth[static_cast<size_t>(active)], truth);
        const Vec3 m = Lr * Vec3(unit(rng), unit(rng), unit(rng));
        filter.update(active, Pose2(rel.x + m.x(), rel.y + m.y(), rel.theta + m.z()), R, 16.27);
      }
      if (k % 4 == 3) {
        filter.addKeyframe(static_cast<int64_t>(keyframe_truth.size()));
        keyframe_truth.push_back(truth);
      }
    }
  }
  out.end_error_before = (filter.robotPose().translation() - truth.translation()).norm();
  if (try_wrong_closure) {
    // A plausible but wrong match: the robot is claimed to be 1.5 m off along the corridor.
    const Pose2 wrong = between(keyframe_truth[0], truth) * Pose2(1.5, 0.0, 0.0);
    out.wrong_closure_accepted = filter.update(0, wrong, R, 16.27).accepted;
  }
  const Pose2 rel = between(keyframe_truth[0], truth);
  const Vec3 m = Lr * Vec3(unit(rng), unit(rng), unit(rng));
  out.closure_accepted = filter.update(0, Pose2(rel.x + m.x(), rel.y + m.y(), rel.theta + m.z()), R, 16.27).accepted;
  out.end_error_after = (filter.robotPose().translation() - truth.translation()).norm();
  Vec3 e = filter.robotPose().vec() - truth.vec();
  e.z() = wrapAngle(e.z());
  out.nees_robot = e.dot(filter.robotCovariance().inverse() * e);
  return out;
}

TEST(PsmSlamFilter, ClosingALoopIsConsistentWithTheTruth) {
  const int runs = 40;
  double nees = 0.0, before = 0.0, after = 0.0;
  int accepted = 0;
  for (int seed = 0; seed < runs; ++seed) {
    const LoopOutcome o = runSyntheticLoop(static_cast<uint64_t>(seed), false);
    nees += o.nees_robot;
    before += o.end_error_before;
    after += o.end_error_after;
    accepted += o.closure_accepted ? 1 : 0;
  }
  EXPECT_GE(accepted, runs - 1);  // a 99.9 % gate passes the right closure (almost) always
  EXPECT_LT(after, 0.5 * before);
  // Average NEES of a consistent 3-dof estimate is 3; the 99 % band of the mean of 40 draws.
  const double mean_nees = nees / runs;
  EXPECT_GT(mean_nees, chiSquaredQuantile(0.005, 3.0 * runs) / runs);
  EXPECT_LT(mean_nees, chiSquaredQuantile(0.995, 3.0 * runs) / runs);
}

TEST(PsmSlamFilter, GateRejectsAWrongClosure) {
  int wrong_accepted = 0;
  for (int seed = 0; seed < 20; ++seed) wrong_accepted += runSyntheticLoop(100 + static_cast<uint64_t>(seed), true).wrong_closure_accepted;
  EXPECT_EQ(wrong_accepted, 0);
}

TEST(PsmSlamFilter, RemovingAKeyframeKeepsTheOthersMarginals) {
  PsmSlamFilter filter;
  filter.reset(Pose2(), Mat3::Zero());
  for (int k = 0; k < 5; ++k) {
    filter.addKeyframe(k);
    filter.predict(Pose2(0.5, 0.0, 0.1), diag3(1e-3, 1e-3, 1e-3));
    filter.update(k, Pose2(0.49, 0.01, 0.1), diag3(1e-4, 1e-4, 1e-4), 1e9);
  }
  const Mat3 cov3 = filter.keyframeCovariance(3);
  const Pose2 pose3 = filter.keyframePose(3);
  const RelativePosePrediction rel3 = filter.predictRelative(3);
  filter.removeKeyframe(1);
  EXPECT_FALSE(filter.hasKeyframe(1));
  EXPECT_EQ(filter.keyframeCount(), 4u);
  EXPECT_LT((filter.keyframeCovariance(3) - cov3).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((filter.keyframePose(3).vec() - pose3.vec()).norm(), 1e-15);
  EXPECT_LT((filter.predictRelative(3).cov - rel3.cov).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_THROW(filter.removeKeyframe(4), std::logic_error);  // the active one
  EXPECT_THROW(filter.predictRelative(1), std::out_of_range);
  // The freed slot is reused: the state does not grow.
  const size_t dimension = filter.dimension();
  filter.addKeyframe(5);
  EXPECT_EQ(filter.dimension(), dimension);
  EXPECT_LT((filter.keyframePose(5).vec() - filter.robotPose().vec()).norm(), 1e-15);
}

TEST(PsmSlamFilter, NewPosesMoveTheRobotWithItsKeyframe) {
  PsmSlamFilter filter;
  filter.reset(Pose2(), Mat3::Zero());
  filter.addKeyframe(0);
  filter.predict(Pose2(2.0, 0.0, 0.0), diag3(1e-2, 1e-2, 1e-2));
  filter.addKeyframe(1);
  filter.predict(Pose2(1.0, 0.0, M_PI / 2), diag3(1e-2, 1e-2, 1e-2));
  filter.setKeyframePoses({{1, Pose2(2.0, 1.0, M_PI / 2)}, {42, Pose2(9, 9, 9)}});
  // The robot was 1 m ahead of keyframe 1, turned by 90°; keyframe 1 now faces +y.
  EXPECT_NEAR(filter.robotPose().x, 2.0, 1e-12);
  EXPECT_NEAR(filter.robotPose().y, 2.0, 1e-12);
  EXPECT_NEAR(filter.robotPose().theta, M_PI, 1e-12);
  EXPECT_NEAR(filter.keyframePose(0).x, 0.0, 1e-12);
}

/// The same random run of predictions, updates, new and removed keyframes, for two filters.
void driveAtRandom(std::mt19937_64& rng, PsmSlamFilter& filter, int steps, int64_t& next_id) {
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int step = 0; step < steps; ++step) {
    filter.predict(Pose2(0.2 + 0.05 * unit(rng), 0.02 * unit(rng), 0.1 * unit(rng)), diag3(4e-4, 1e-4, 3e-4));
    const double choice = uniform(rng);
    if (choice < 0.15) {
      filter.addKeyframe(next_id++);
    } else if (choice < 0.2 && filter.keyframeCount() > 3) {
      const int64_t oldest = next_id - static_cast<int64_t>(filter.keyframeCount()) - 1;
      for (int64_t id = 0; id < next_id; ++id)
        if (id != filter.activeKeyframe() && id > oldest && filter.hasKeyframe(id)) {
          filter.removeKeyframe(id);
          break;
        }
    } else {
      int64_t k = filter.activeKeyframe();
      if (choice > 0.8) {
        k = static_cast<int64_t>(uniform(rng) * static_cast<double>(next_id));
        if (!filter.hasKeyframe(k)) k = filter.activeKeyframe();
      }
      const Pose2 guess = filter.predictRelative(k).mean;
      filter.update(k, Pose2(guess.x + 0.03 * unit(rng), guess.y + 0.03 * unit(rng), guess.theta + 0.01 * unit(rng)),
                    diag3(1e-3, 2e-3, 2e-4), 1e9);
    }
  }
}

TEST(PsmSlamFilter, ARestoredStateGoesOnAsTheFilterItCameFrom) {
  std::mt19937_64 rng(5);
  PsmSlamFilter original;
  original.reset(Pose2(0.5, -0.2, 0.3), diag3(1e-3, 2e-3, 1e-4));
  original.addKeyframe(0);
  int64_t next_id = 1;
  driveAtRandom(rng, original, 80, next_id);
  // Two freed slots, which the export compacts, and updates pending, which it applies to a copy.
  for (int removed = 0, id = 0; removed < 2; ++id)
    if (original.hasKeyframe(id) && id != original.activeKeyframe()) {
      original.removeKeyframe(id);
      ++removed;
    }
  original.predict(Pose2(0.3, 0.0, 0.05), diag3(4e-4, 1e-4, 3e-4));
  // An innovation, so that the pending update moves the other keyframes too.
  original.update(original.activeKeyframe(), original.predictRelative(original.activeKeyframe()).mean * Pose2(0.02, -0.01, 0.004),
                  diag3(1e-3, 2e-3, 2e-4), 1e9);
  const size_t flushes = original.flushCount();
  const PsmSlamFilterState state = original.exportState();
  EXPECT_EQ(original.flushCount(), flushes);
  ASSERT_EQ(state.ids.size(), original.keyframeCount());
  EXPECT_LT(state.ids.size() + 1, original.dimension() / 3) << "the run should free slots, so that they are compacted";

  PsmSlamFilter restored;
  restored.restore(state);
  EXPECT_EQ(restored.activeKeyframe(), original.activeKeyframe());
  EXPECT_EQ(restored.dimension(), 3 * (state.ids.size() + 1));
  std::mt19937_64 same_rng = rng;
  int64_t same_next_id = next_id;
  driveAtRandom(rng, original, 40, next_id);
  driveAtRandom(same_rng, restored, 40, same_next_id);
  EXPECT_LT((restored.robotPose().vec() - original.robotPose().vec()).norm(), 1e-9);
  EXPECT_LT((restored.robotCovariance() - original.robotCovariance()).cwiseAbs().maxCoeff(), 1e-12);
  for (int64_t id = 0; id < next_id; ++id) {
    ASSERT_EQ(restored.hasKeyframe(id), original.hasKeyframe(id)) << id;
    if (!original.hasKeyframe(id)) continue;
    EXPECT_LT((restored.keyframePose(id).vec() - original.keyframePose(id).vec()).norm(), 1e-9) << id;
    EXPECT_LT((restored.predictRelative(id).cov - original.predictRelative(id).cov).cwiseAbs().maxCoeff(), 1e-12) << id;
  }
}

TEST(PsmSlamFilter, AStateThatIsNotOneIsRefused) {
  PsmSlamFilter filter;
  filter.reset(Pose2(), diag3(1e-3, 1e-3, 1e-3));
  filter.addKeyframe(7);
  filter.predict(Pose2(1.0, 0.0, 0.1), diag3(1e-3, 1e-3, 1e-3));
  filter.addKeyframe(9);
  const PsmSlamFilterState good = filter.exportState();
  PsmSlamFilter other;
  other.restore(good);

  PsmSlamFilterState short_mean = good;
  short_mean.mean.conservativeResize(6);
  EXPECT_THROW(other.restore(short_mean), std::invalid_argument);
  PsmSlamFilterState twice = good;
  twice.ids = {7, 7};
  EXPECT_THROW(other.restore(twice), std::invalid_argument);
  PsmSlamFilterState no_active = good;
  no_active.active = 8;
  EXPECT_THROW(other.restore(no_active), std::invalid_argument);
  PsmSlamFilterState not_finite = good;
  not_finite.cov(4, 2) = std::nan("");
  EXPECT_THROW(other.restore(not_finite), std::invalid_argument);
  PsmSlamFilterState negative = good;
  negative.cov(4, 4) = -1e-6;
  EXPECT_THROW(other.restore(negative), std::invalid_argument);
  PsmSlamFilterState overcorrelated = good;
  overcorrelated.cov(4, 1) = overcorrelated.cov(1, 4) = 1.5 * std::sqrt(good.cov(1, 1) * good.cov(4, 4));
  EXPECT_THROW(other.restore(overcorrelated), std::invalid_argument);
}

}  // namespace
}  // namespace polarslam
