#pragma once
// The EKF SLAM state (thesis §3.5): robot pose (x, y, θ) followed by the map features, each a
// block of 2 (line α, d; point x, y) or 3 (corner x, y, γ) entries, with the full covariance.
//
// Every observation depends on the robot and one feature only, so H has two non-zero blocks per
// row. Predictions touch only the robot rows and columns (O(n)); updates form P·Hᵀ from the
// robot and feature columns (O(n·m)) and subtract a rank-m product from P (O(n²·m)); the full
// n×n products of the textbook formulas are never built.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "geometry/pose2.hpp"
#include "odometry/odometry_model.hpp"
#include "slam/feature_map.hpp"

namespace polarslam {

/// One feature block in the state.
struct StateFeature {
  int64_t id = 0;
  MapFeatureKind kind = MapFeatureKind::Line;
  int offset = 0;  ///< index of its first entry in the state vector
  int size() const { return parameterCount(kind); }
};

/// An observation linearised against one state feature: z ≈ h + H_x·δx_v + H_y·δy.
/// Rows beyond `dim` and columns beyond the feature's size are zero.
struct LinearizedObservation {
  int feature = -1;  ///< index into EkfState::features()
  int dim = 2;       ///< 2, or 3 for a corner observed with its orientation
  Vec3 innovation = Vec3::Zero();  ///< z − h(x̂), angles wrapped
  Mat3 H_x = Mat3::Zero();
  Mat3 H_y = Mat3::Zero();
  Mat3 R = Mat3::Zero();
};

class EkfState {
 public:
  explicit EkfState(const Pose2& start = {}, const Mat3& start_cov = Mat3::Zero());

  Pose2 pose() const { return {mean_(0), mean_(1), mean_(2)}; }
  Mat3 poseCovariance() const { return cov_.topLeftCorner<3, 3>(); }
  /// The state vector and covariance (views into storage that grows by doubling, so that adding
  /// a feature does not copy the whole covariance every time).
  Eigen::VectorBlock<const Eigen::VectorXd> mean() const { return mean_.head(n_); }
  Eigen::Block<const Eigen::MatrixXd> covariance() const { return cov_.topLeftCorner(n_, n_); }
  const std::vector<StateFeature>& features() const { return features_; }
  int dimension() const { return n_; }

  /// Feature parameters (unused entries 0) and the marginal covariance block.
  Vec3 featureMean(int feature) const;
  Mat3 featureCovariance(int feature) const;
  /// Cross-covariance P(robot, feature) (3 × size, padded to 3 × 3).
  Mat3 robotFeatureCovariance(int feature) const;

  /// Prediction with an odometry motion: x_v ← x_v ⊕ Δ, robot rows and columns of P propagated
  /// with J_a = ∂(x_v ⊕ Δ)/∂x_v (the F_x of docs/algorithms.md §17.6) and Q = J_b·Σ_Δ·J_bᵀ.
  void predict(const OdometryMotion& motion);

  /// Innovation covariance H·P·Hᵀ + R of one linearised observation (dim × dim, padded).
  Mat3 innovationCovariance(const LinearizedObservation& o) const;
  /// H_a·P·H_bᵀ for two linearised observations (the off-diagonal block of a joint S).
  Mat3 crossCovariance(const LinearizedObservation& a, const LinearizedObservation& b) const;

  /// Batch EKF update with all observations at once (each against a different feature or not —
  /// correctness does not need it). Returns false and changes nothing when the joint innovation
  /// covariance is not positive definite.
  bool update(const std::vector<LinearizedObservation>& observations);

  /// Appends a feature initialised from a robot-frame observation z with covariance R through
  /// g(x_v, z) (App. B): P_yy = G_x·P_vv·G_xᵀ + G_z·R·G_zᵀ, P_y· = G_x·P_v·. Returns its index.
  int addFeature(int64_t id, MapFeatureKind kind, const Vec3& y, const Mat3& G_x, const Mat3& G_z, const Mat3& R);

 private:
  /// P·Hᵀ for one observation, n × dim.
  Eigen::MatrixXd covarianceTimesHt(const LinearizedObservation& o) const;
  void wrapAngles();
  void reserve(int dimension);

  int n_ = 3;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd cov_;
  std::vector<StateFeature> features_;
};

}  // namespace polarslam
