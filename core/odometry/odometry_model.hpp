#pragma once
// Odometry error model of docs/algorithms.md §17.6 (thesis §3.4; reconstruction after [KODO, CK97]):
// zero-mean white wheel-distance errors with per-wheel variance proportional to the distance the
// wheel rolled, σ_R² = k_R·|Δs_R|, σ_L² = k_L·|Δs_L|, propagated through the differential-drive
// midpoint model
//   Δs = (Δs_R + Δs_L)/2,  Δθ = (Δs_R − Δs_L)/B,  μ = θ + Δθ/2,
//   x ← x + Δs·cos μ,  y ← y + Δs·sin μ,  θ ← θ + Δθ,
//   P ← F_x·P·F_xᵀ + F_u·diag(σ_R², σ_L²)·F_uᵀ.
// Logs that record only odometry poses (CARMEN) give (Δs, Δθ) from consecutive poses, with
// variances proportional to distance and turned angle plus a small floor.
//
// KODO integrates the covariance in closed form over whole constant-curvature arcs. Here an
// increment between two readings is taken as one constant-curvature arc and cut into short
// sub-steps, which converges to the same integral (a one-step update would under-state e.g. the
// lateral variance of a straight run by a quarter: L²σ_θ²/4 instead of L²σ_θ²/3).
#include <Eigen/Core>
#include <optional>
#include <string>

#include "geometry/pose2.hpp"
#include "odometry/odometry_reading.hpp"

namespace polarslam {

using Mat32 = Eigen::Matrix<double, 3, 2>;

struct WheelErrorParams {
  double wheelbase = 0.5;  ///< B, m: distance between the wheel contact points
  double k_right = 1e-4;   ///< m (m²/m): σ_R² = k_right·|Δs_R|
  double k_left = 1e-4;    ///< m (m²/m)
};

/// Variance law for increments derived from recorded poses (no wheel travel in the log).
struct PoseIncrementErrorParams {
  double k_distance = 1e-4;          ///< m²/m: σ_Δs² grows by this per metre travelled
  double k_heading_per_rad = 1e-3;   ///< rad²/rad: σ_Δθ² per radian turned
  double k_heading_per_m = 1e-4;     ///< rad²/m: σ_Δθ² per metre travelled (drift while driving)
  double min_distance_sigma = 1e-3;  ///< m: floor of σ_Δs for every increment
  double min_heading_sigma = 1e-3;   ///< rad: floor of σ_Δθ for every increment
};

enum class OdometrySource {
  Auto,         ///< wheel travel when the readings carry any (non-zero) wheel travel, else poses
  WheelTravel,  ///< cumulative left/right wheel travel
  Pose,         ///< consecutive odometry poses
};

struct OdometryModelParams {
  OdometrySource source = OdometrySource::Auto;
  WheelErrorParams wheels;
  PoseIncrementErrorParams poses;
  double max_translation = 2.0;      ///< m: larger increments between two readings are rejected ...
  double max_rotation = 1.6;         ///< rad: larger heading changes are rejected ...
  double max_speed = 2.0;            ///< m/s: ... unless the readings are far enough apart in time
  double max_turn_rate = 3.0;        ///< rad/s: ... for that
  /// s: readings further apart (a restart, a dropped stretch) are not taken as one arc of the
  /// wheels: the increment is the odometry poses' difference, which holds whatever the path.
  double max_arc_interval = 0.5;
  double max_substep_length = 0.05;  ///< m: sub-step length when integrating an arc
  double max_substep_angle = 0.05;   ///< rad: sub-step heading change when integrating an arc
};

/// Throws std::invalid_argument naming the first bad parameter.
void validate(const OdometryModelParams& params);

struct MotionJacobians {
  Mat3 F_x;   ///< ∂(new pose)/∂(old pose)
  Mat32 F_u;  ///< ∂(new pose)/∂(Δs_R, Δs_L)
};

/// The midpoint model's step for wheel travels (Δs_R, Δs_L).
Pose2 differentialDriveStep(const Pose2& pose, double ds_right, double ds_left, double wheelbase);
/// F_x and F_u of docs/algorithms.md §17.6 at `pose` for wheel travels (Δs_R, Δs_L).
MotionJacobians differentialDriveJacobians(const Pose2& pose, double ds_right, double ds_left, double wheelbase);
/// diag(k_R|Δs_R|, k_L|Δs_L|).
Mat2 wheelTravelCovariance(double ds_right, double ds_left, const WheelErrorParams& params);
/// One step of docs/algorithms.md §17.6: moves `pose` and propagates `covariance` in place (no sub-steps).
void propagateWheelStep(Pose2& pose, Mat3& covariance, double ds_right, double ds_left, const WheelErrorParams& params);

/// The midpoint model's step for a forward distance and heading change.
Pose2 unicycleStep(const Pose2& pose, double ds, double dtheta);
/// ∂(new pose)/∂(old pose) of unicycleStep (the F_x of §17.6).
Mat3 unicycleStateJacobian(const Pose2& pose, double ds, double dtheta);
/// ∂(new pose)/∂(Δs, Δθ) of unicycleStep.
Mat32 unicycleInputJacobian(const Pose2& pose, double ds, double dtheta);

/// Relative motion between two odometry readings with its uncertainty.
struct OdometryMotion {
  double ds = 0.0;      ///< m, signed forward distance along the arc (robot centre)
  double dtheta = 0.0;  ///< rad, heading change
  Pose2 delta;          ///< SE(2) increment in the frame of the first reading's pose
  Mat3 cov = Mat3::Zero();  ///< covariance of delta, in the frame of the first reading's pose
  OdometrySource source = OdometrySource::WheelTravel;  ///< the one actually used
};

enum class OdometryFault { None, NonFinite, TimeWentBackwards, TooLarge };

/// Either a motion or a reason why there is none (fault != None, error says what happened).
struct OdometryMotionResult {
  std::optional<OdometryMotion> motion;
  OdometryFault fault = OdometryFault::None;
  std::string error;
  bool ok() const { return motion.has_value(); }
};

/// Motion from `from` to `to`. Non-finite values, time going backwards and increments beyond
/// max_translation/max_rotation give an error result; nothing throws for bad readings.
OdometryMotionResult odometryMotion(const OdometryReading& from, const OdometryReading& to,
                                    const OdometryModelParams& params);

/// EKF prediction with a motion: pose ← pose ⊕ delta,
/// P ← J_a·P·J_aᵀ + J_b·Q·J_bᵀ (J_a, J_b the Jacobians of ⊕; J_a equals F_x of §17.6).
void applyMotion(Pose2& pose, Mat3& covariance, const OdometryMotion& motion);

/// Follows a stream of odometry readings: the motion since the previous accepted reading, and the
/// integrated pose and covariance in the odometry frame (starting at the first reading's pose
/// with zero covariance).
class OdometryIntegrator {
 public:
  explicit OdometryIntegrator(OdometryModelParams params = {});

  /// The motion since the previous accepted reading (the first reading gives a zero motion).
  /// A reading with non-finite values or an earlier timestamp is rejected and forgotten. A
  /// reading that jumps too far is rejected too, but becomes the new baseline, so that one bad
  /// gap does not reject every later reading; the integrated pose does not move.
  OdometryMotionResult add(const OdometryReading& reading);

  bool started() const { return last_.has_value(); }
  const Pose2& pose() const { return pose_; }
  const Mat3& covariance() const { return covariance_; }
  size_t rejected() const { return rejected_; }
  const OdometryModelParams& params() const { return params_; }

 private:
  OdometryModelParams params_;
  std::optional<OdometryReading> last_;
  Pose2 pose_;
  Mat3 covariance_ = Mat3::Zero();
  size_t rejected_ = 0;
};

}  // namespace polarslam
