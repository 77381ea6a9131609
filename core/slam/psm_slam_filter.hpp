#pragma once
// The Kalman filter of PSM SLAM (docs/algorithms.md §18): a delayed-state EKF whose state is the current robot
// pose plus the poses of the stored reference scans (keyframes). Prediction composes the odometry
// motion (§17.6 model); an observation is a scan match: the robot pose relative to one keyframe,
// with the match covariance.
//
// Cost. Almost every step touches only the robot and the keyframe it is matched against (the
// "active" keyframe), so the filter runs as a compressed EKF (Guivant & Nebot 2001): predictions
// and updates are exact 6-dimensional operations on that pair, and their effect on the rest of
// the state is accumulated in three small matrices and applied in one O(n²) pass only when the
// active keyframe changes (a new keyframe, a switch, a loop closure). The result equals the full
// EKF's at every step (tests/unit/psm_slam check it against a plain dense EKF).
//
// Keyframes sit in slots of one dense covariance matrix; a marginalised keyframe frees its slot.
#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

/// Relative pose of the robot seen from a keyframe, v(⊖k ⊕ r), with its covariance from the filter.
struct RelativePosePrediction {
  Pose2 mean;
  Mat3 cov = Mat3::Zero();
};

/// v(⊖k ⊕ r) as predictRelative gives it, with bounds on its standard deviations that need no
/// covariance product: along any direction of its translation, and of its heading.
struct RelativePoseBound {
  Pose2 mean;
  double position_sigma = 0.0;  ///< m, ≥ √(uᵀ·cov_xy·u) for the direction u of mean's translation
  double heading_sigma = 0.0;   ///< rad, ≥ √cov(2, 2)
};

struct FilterUpdateOutcome {
  bool accepted = false;
  double chi2 = 0.0;  ///< νᵀS⁻¹ν of the innovation (3 degrees of freedom)
};

/// ∂v(⊖k ⊕ r)/∂r and ∂v(⊖k ⊕ r)/∂k.
struct RelativePoseJacobians {
  Mat3 robot, keyframe;
};
RelativePoseJacobians relativePoseJacobians(const Pose2& keyframe, const Pose2& robot);

/// The whole filter, for a crash-recovery snapshot: the robot and every keyframe with all their
/// correlations, so that a resumed run goes on exactly as the killed one would have.
struct PsmSlamFilterState {
  std::vector<int64_t> ids;  ///< keyframes, in the order of `mean` and `cov` after the robot
  Eigen::VectorXd mean;      ///< robot, then the keyframes: 3 + 3·ids.size()
  Eigen::MatrixXd cov;       ///< the joint covariance of `mean`
  int64_t active = -1;
};

class PsmSlamFilter {
 public:
  /// Starts over with the robot at `pose` with covariance `cov` and no keyframes.
  void reset(const Pose2& pose, const Mat3& cov);

  /// robot ← robot ⊕ motion, motion_cov the covariance of motion in the robot frame.
  void predict(const Pose2& motion, const Mat3& motion_cov);

  /// Stores the robot's current pose as keyframe `id` (new) and makes it the active keyframe.
  void addKeyframe(int64_t id);
  /// Adds keyframe `id` at `pose` with covariance `cov`, independent of the robot and of the other
  /// keyframes (a reference scan of a saved map). The active keyframe stays.
  void addIndependentKeyframe(int64_t id, const Pose2& pose, const Mat3& cov);
  /// Marginalises a keyframe out of the filter (the pose graph keeps it). Not the active one.
  void removeKeyframe(int64_t id);
  /// Makes `id` the keyframe the next updates are expected to involve.
  void setActiveKeyframe(int64_t id);

  /// v(⊖k ⊕ r) and its covariance J·P·Jᵀ, without the measurement noise. O(1) for any keyframe.
  RelativePosePrediction predictRelative(int64_t id) const;
  /// The same mean with bounds on its spread, for ruling keyframes out before predictRelative.
  RelativePoseBound boundRelative(int64_t id) const;
  /// EKF update with a measurement z of v(⊖k ⊕ r) with covariance R. The update is applied only
  /// when νᵀS⁻¹ν ≤ chi2_gate (pass +inf to always apply it).
  FilterUpdateOutcome update(int64_t id, const Pose2& z, const Mat3& R, double chi2_gate);

  /// Replaces keyframe means (e.g. with optimised pose-graph poses); the robot moves rigidly
  /// with the active keyframe. Covariances are kept. Ids not in the filter are ignored.
  void setKeyframePoses(const std::unordered_map<int64_t, Pose2>& poses);

  Pose2 robotPose() const { return Pose2(local_x_.head<3>()); }
  Mat3 robotCovariance() const { return local_P_.topLeftCorner<3, 3>(); }
  Pose2 keyframePose(int64_t id) const;
  Mat3 keyframeCovariance(int64_t id) const;

  bool hasKeyframe(int64_t id) const { return slot_of_.count(id) != 0; }
  int64_t activeKeyframe() const { return active_id_; }
  size_t keyframeCount() const { return slot_of_.size(); }
  /// Dimension of the stored state (3 per used slot, robot included).
  size_t dimension() const { return 3 * slot_end_; }
  /// How many O(n²) passes (compressed updates applied to the whole state) have run.
  size_t flushCount() const { return flushes_; }

  /// The whole state with its pending updates applied; the filter itself is left as it is, so
  /// that taking a snapshot does not change the run's rounding.
  PsmSlamFilterState exportState() const;
  /// Replaces the filter with `state`. Throws std::invalid_argument on a state that is not one
  /// (sizes that disagree, a keyframe twice, an active keyframe it lacks, a non-finite value).
  void restore(const PsmSlamFilterState& state);

  /// The full state mean and covariance (applies pending updates first); for tests and tools.
  Eigen::VectorXd stateMean();
  Eigen::MatrixXd stateCovariance();

 private:
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat36 = Eigen::Matrix<double, 3, 6>;

  /// Applies the accumulated local updates to the whole state and restarts accumulation.
  void flush();
  void loadLocal();
  size_t slotOf(int64_t id) const;
  size_t allocateSlot();
  void ensureCapacity(size_t slots);
  /// Index of the first state element of a slot (slot 0 is the robot).
  static Eigen::Index offset(size_t slot) { return static_cast<Eigen::Index>(3 * slot); }

  /// 3×3 block (row slot offset s, column t) of the whole covariance at the last flush.
  Mat3 block(Eigen::Index s, Eigen::Index t) const;
  void setBlock(Eigen::Index s, Eigen::Index t, const Mat3& value);
  /// The n×3 column of slot offset t, and writing one (its row too: P is symmetric).
  Eigen::MatrixXd column(Eigen::Index t) const;
  void setColumn(Eigen::Index t, const Eigen::MatrixXd& value);

  // Whole state at the last flush: slot 0 = robot, slot s ≥ 1 = a keyframe or free (zeros).
  // Only P_'s lower triangle is kept (block() and column() read it): a flush updates half the
  // elements, and the flushes are most of PSM SLAM's time over a long run.
  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  size_t slot_end_ = 1;  ///< one past the highest slot ever used
  std::vector<size_t> free_slots_;
  std::unordered_map<int64_t, size_t> slot_of_;
  int64_t active_id_ = -1;
  size_t active_slot_ = 0;  ///< 0 = no active keyframe (then there are no keyframes)

  // Local pair A = (robot, active keyframe), exact, and the compressed effect on the rest B:
  // P_AB = Φ·P_AB(0), P_BB = P_BB(0) − P_BA(0)·Ψ·P_AB(0), x_B = x_B(0) + P_BA(0)·θ.
  Vec6 local_x_ = Vec6::Zero();
  Mat6 local_P_ = Mat6::Zero();
  Mat6 phi_ = Mat6::Identity();
  Mat6 psi_ = Mat6::Zero();
  Vec6 theta_ = Vec6::Zero();
  bool pending_ = false;  ///< Φ, Ψ, θ differ from (I, 0, 0)
  size_t flushes_ = 0;
};

}  // namespace polarslam
