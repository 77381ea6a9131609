#pragma once
// Pose regeneration (thesis §3.7.2, docs/algorithms.md §17.10): a scan's pose is re-solved in the *current*
// SLAM map by weighted least squares of the features stored with it (robot-frame observations
// at scan time) against those features' current map estimates:
//   x* = argmin Σ_i (z_i − h(x, y_i))ᵀ (R_i + H_y P_i H_yᵀ)⁻¹ (z_i − h(x, y_i))
// solved by Gauss–Newton with the App. B H_x, angle residuals wrapped. Scans whose anchors
// do not pin down all three degrees of freedom fall back to a chained estimate.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "slam/feature_map.hpp"

namespace polarslam {

enum class PoseSource : int8_t {
  Regenerated = 0,  ///< solved from its own anchors in the current map
  Chained = 1,      ///< too few anchors: the correction of the nearest regenerated scan applied
  Stored = 2,       ///< no regenerated scan at all: the SLAM pose at scan time
};

const char* poseSourceName(PoseSource source);

struct RegenerationOptions {
  int max_iterations = 20;
  /// Rank test: the solution must pin position to this standard deviation (m) and heading to
  /// `max_heading_sigma` (rad) in every direction, or the scan is under-constrained.
  double max_position_sigma = 0.10;
  double max_heading_sigma = deg2rad(3.0);
  double min_line_distance = 0.05;  ///< m: lines nearer the robot are skipped (flip discontinuity)
  /// Anchors whose normalised squared residual exceeds the χ² 99.9 % quantile are dropped
  /// one at a time (a feature merged or re-estimated wrongly must not drag the pose).
  bool reject_outliers = true;
  bool include_map_covariance = true;  ///< add H_y P H_yᵀ of the current map feature
};

struct RegeneratedPose {
  Pose2 pose;
  Mat3 cov = Mat3::Zero();   ///< (Σ H_xᵀ W H_x)⁻¹ when regenerated; the source's otherwise
  PoseSource source = PoseSource::Stored;
  int anchors_used = 0;      ///< anchors in the final fit
  int anchors_rejected = 0;  ///< outliers dropped
  int iterations = 0;
  double chi2 = 0.0;         ///< final Σ rᵀ W r
};

/// Current map features by id.
using FeatureIndex = std::unordered_map<int64_t, const MapFeature*>;
FeatureIndex indexFeatures(const FeatureMap& map);

/// Re-solves one scan's pose from its own anchors. Starts from the stored SLAM pose. Returns
/// source Regenerated on success, otherwise source Stored with the stored pose.
RegeneratedPose regeneratePose(const ScanAnchors& anchors, const FeatureIndex& map,
                               const RegenerationOptions& options = {});

/// Regenerates every pose (anchors in time order). An under-constrained scan gets the
/// correction (new ⊕ old⁻¹) of the regenerated scan nearest in time applied to its stored pose.
std::vector<RegeneratedPose> regeneratePoses(const std::vector<const ScanAnchors*>& anchors, const FeatureMap& map,
                                             const RegenerationOptions& options = {});
std::vector<RegeneratedPose> regeneratePoses(const std::vector<ScanAnchors>& anchors, const FeatureMap& map,
                                             const RegenerationOptions& options = {});

struct RegenerationSummary {
  int regenerated = 0, chained = 0, stored = 0;
  int anchors_rejected = 0;
  double mean_shift = 0.0, max_shift = 0.0;  ///< m: regenerated vs stored position
};
RegenerationSummary summarize(const std::vector<const ScanAnchors*>& anchors, const std::vector<RegeneratedPose>& poses);

}  // namespace polarslam
