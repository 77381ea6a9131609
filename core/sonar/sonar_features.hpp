#pragma once
// Advanced-sonar targets as features in the robot base frame (docs/algorithms.md §17.3; reconstruction):
//  - plane → line: the echo returns along the plane's normal, so in the array frame the line is
//    (α, d) = (ψ, ρ) for bearing ψ and range ρ;
//  - corner → right-angle corner: the double reflection comes from the apex; the sonar does not
//    measure the corner's orientation, so γ carries kUnknownAngleVariance (see below);
//  - edge → point at the measured range and bearing;
//  - unknown → dropped (counted).
// Covariances: diag(σ_ρ², σ_ψ²) (the target's own, floored at the still-air accuracy of [K95])
// through the Jacobian of the array-frame → base-frame transform, plus the mount pose
// covariance through the Jacobian with respect to the mount pose.
//
// Corner orientation: the array can only see a concave corner from inside its 90° wedge, so
// the bisector lies within ±45° of the apex→array direction, and γ is set to that direction.
// Its variance stays "unknown" on purpose: an array that watches the corner from one place
// would report the same ±45°-wrong γ every cycle, and a filter that took those as independent
// measurements would pull the robot heading toward the bias (H_x of γ_r is −1 on θ).
#include "geometry/features.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

struct SonarFeatureParams {
  double range_sigma_floor = 0.001;             ///< m: [K95] still-air accuracy
  double bearing_sigma_floor = deg2rad(0.1);    ///< rad
  Mat3 mount_cov = Mat3::Zero();                ///< uncertainty of the array mount (x, y, yaw)
  double min_range = 0.05;                      ///< m: closer targets are rejected
};

struct SonarFeatureCounts {
  int unknown = 0;  ///< targets classified "unknown"
  int invalid = 0;  ///< non-finite, out-of-range or unknown-kind targets, bad covariances
};

/// (range, bearing) covariance of a target with the floors applied; false when unusable.
bool sonarTargetCovariance(const SonarTarget& target, const SonarFeatureParams& params, Mat2& cov);

LineFeature sonarPlaneLine(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                           const Mat3& mount_cov);
PointFeature sonarEdgePoint(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                            const Mat3& mount_cov);
CornerFeature sonarCornerFeature(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                                 const Mat3& mount_cov);

/// All usable targets of one scan as features in the base frame ("base", stamped with the scan).
FeatureSet sonarFeatures(const SonarScan& scan, const SonarFeatureParams& params, SonarFeatureCounts* counts = nullptr);

}  // namespace polarslam
