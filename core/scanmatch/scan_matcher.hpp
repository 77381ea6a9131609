#pragma once
// Polar Scan Matching (Diosi & Kleeman; docs/algorithms.md §3–§11), its Cartesian variant PSM-C
// (§10) and the simple point-to-point ICP the thesis compared against (§12), natively in the
// polarslam frame (x forward, SI). A ScanMatcher owns reusable work buffers: one instance per
// thread, no allocation per match once the buffers have grown to the scan size.
//
//   PsmParams params;
//   PreparedScan ref = prepareScan(scan_a, params), cur = prepareScan(scan_b, params);
//   ScanMatcher matcher(params);
//   MatchResult m = matcher.match(ref, cur, guess);   // guess: current laser pose in the reference laser frame
#include <array>
#include <string>
#include <vector>

#include "geometry/pose2.hpp"
#include "scanmatch/match_sums.hpp"
#include "scanmatch/prepared_scan.hpp"
#include "scanmatch/projection.hpp"
#include "scanmatch/psm_params.hpp"
#include "scanmatch/vector_kernels.hpp"

namespace polarslam {

enum class MatchStatus {
  Ok,
  NotEnoughPoints,         ///< fewer than min_valid_points associated bearings (or pairs)
  SingularTranslation,     ///< translation normal matrix (nearly) singular
  OrientationSearchFailed, ///< no shift of the orientation search had enough overlap
  Diverged,                ///< the estimate left any plausible region
};
const char* statusText(MatchStatus status);

struct MatchResult {
  MatchStatus status = MatchStatus::Ok;
  Pose2 pose;                ///< current laser pose in the reference laser frame
  Mat3 cov = Mat3::Zero();   ///< covariance of pose (x, y, θ)
  int iterations = 0;
  int valid_points = 0;      ///< associated bearings (PSM, PSM-C) or trimmed pairs (ICP) at the end
  bool converged = false;    ///< the stop rule fired before the iteration limit
  double error_index = 0.0;  ///< m, mean |range residual| of associated bearings (§11.2 pm_error_index2)
  bool ok() const { return status == MatchStatus::Ok; }
};

class ScanMatcher {
 public:
  explicit ScanMatcher(PsmParams params = {});
  const PsmParams& params() const { return params_; }
  PsmParams& params() { return params_; }

  MatchResult match(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess,
                    MatchMethod method = MatchMethod::Psm);
  MatchResult matchPsm(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess);
  MatchResult matchPsmC(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess);
  MatchResult matchIcp(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess);

  /// Covariance of a converged pose by the configured model (§11); fills cov and error_index.
  void estimateCovariance(const PreparedScan& ref, const PreparedScan& cur, MatchResult& result);
  Mat3 heuristicCovariance(const PreparedScan& ref, double error_index) const;

  /// The vector kernels of the inner loops: the widest the processor has unless set (every
  /// set gives the same bits; tests and benchmarks compare them).
  void useKernels(VectorKernels kernels) { kernels_ = kernels; }

 private:
  struct TranslationStep {
    MatchStatus status = MatchStatus::Ok;
    double dx = 0.0, dy = 0.0;
    int used = 0;
  };
  struct OrientationStep {
    MatchStatus status = MatchStatus::Ok;
    double dtheta = 0.0;
  };
  /// Weighted normal equations of the polar residuals with the surface-consistent 3-DOF
  /// Jacobian (§11.1), plus the sums the covariance and the error index need.
  struct JointSystem {
    Mat3 information = Mat3::Zero();
    Vec3 gradient = Vec3::Zero();
    double sum_w = 0.0, sum_we2 = 0.0;
    int used = 0;
    double error_index = 0.0;
    /// Where the system was set up (the projection it was summed over) and its weighting
    /// factor: the covariance's slope-noise term is summed there too, once, at the end.
    Pose2 pose;
    double c = 0.0;
  };
  struct CartesianStep {
    MatchStatus status = MatchStatus::Ok;
    Pose2 delta;
    int used = 0;
  };

  /// The result every method starts from: the guess, or NotEnoughPoints for a scan too sparse.
  MatchResult startResult(const PreparedScan& ref, const PreparedScan& cur, const Pose2& guess) const;
  bool usableSample(const PreparedScan& ref, size_t j) const;
  /// Associated bearings a step on the way needs (an orientation search's overlap, a translation
  /// step's samples): from a far guess fewer associate, and the step still points the right way.
  double stepMinPoints() const;

  double weightingFactor(int iteration, const PreparedScan& ref) const;
  double projectedErrorIndex(const PreparedScan& ref) const;
  TranslationStep solveTranslation(const PreparedScan& ref, const Pose2& pose, double c);
  /// The sums over the current projection (projection_) at `pose`.
  JointSums jointSums(const PreparedScan& ref, const Pose2& pose, double c, JointTerms terms) const;
  JointSystem jointSystem(const PreparedScan& ref, const Pose2& pose, double c,
                          JointTerms terms = JointTerms::All) const;
  /// JointSums' s11..s33 as a matrix at the system's pose: what slope noise adds to its
  /// information per unit range variance (slope_noise_correction). Reads the projection the
  /// system was summed over.
  Mat3 slopeNoise(const PreparedScan& ref, const JointSystem& system) const;
  Mat3 covarianceFrom(const JointSystem& system, const Mat3& slope_noise) const;
  /// error_index and cov of `result` from the system at its final pose, by the configured model.
  void fillCovariance(const PreparedScan& ref, const JointSystem& system, MatchResult& result) const;
  OrientationStep searchOrientation(const PreparedScan& ref, double window, double c);
  double gradientRefinement(const PreparedScan& ref, int shift, double c) const;
  CartesianStep solveCartesian(const PreparedScan& ref, double c);

  PsmParams params_;
  VectorKernels kernels_ = widestVectorKernels();
  Projection projection_;
  std::vector<float> proj_masked_, proj_mask_;   // orientation search inputs
  std::vector<double> shift_cost_;               // e(k) by k + window
  std::vector<float> coarse_[4];                 // decimated inputs of the coarse search
  std::vector<int> icp_cur_, icp_ref_;           // ICP pairs
  std::vector<double> icp_dist_, icp_sorted_;
};

/// §5 in SE(2) form: the current laser pose in the reference laser frame,
/// (⊖(T_r ⊕ M_r)) ⊕ (T_c ⊕ M_c), from robot poses T and laser mounts M.
Pose2 laserPoseInReferenceLaser(const Pose2& robot_ref, const Pose2& robot_cur, const Pose2& mount_ref,
                                const Pose2& mount_cur);
/// Back to robot motion: (⊖T_r) ⊕ T_c = M_r ⊕ laser_motion ⊕ (⊖M_c).
Pose2 robotMotionFromLaserMotion(const Pose2& laser_motion, const Pose2& mount_ref, const Pose2& mount_cur);
/// Covariance of that robot motion, J·Σ·Jᵀ with J the Jacobian of the composition.
Mat3 robotMotionCovariance(const Pose2& laser_motion, const Mat3& laser_cov, const Pose2& mount_ref,
                           const Pose2& mount_cur);

}  // namespace polarslam
