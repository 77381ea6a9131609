#pragma once
// Moving measured features from one robot-attached frame to another: a sensor frame into the
// robot base frame (T = the mount pose), or the base frame at one time into the base frame at
// another (T = the relative motion from odometry). The feature covariances go through the
// Jacobian of the transform, and an uncertain T adds J_T·Σ_T·J_Tᵀ (App. B's g() and its G_z,
// G_x with T in the role of the robot pose).
#include "geometry/features.hpp"

namespace polarslam {

/// Line (α, d) given in frame B, with T = pose of B in A; the result in A, d ≥ 0.
LineFeature transformLine(const LineFeature& line, const Pose2& T, const Mat3& T_cov = Mat3::Zero());
CornerFeature transformCorner(const CornerFeature& corner, const Pose2& T, const Mat3& T_cov = Mat3::Zero());
PointFeature transformPoint(const PointFeature& point, const Pose2& T, const Mat3& T_cov = Mat3::Zero());

/// Every feature of `set` moved by T; frame and sensor_pose are left for the caller to set.
FeatureSet transformFeatures(const FeatureSet& set, const Pose2& T, const Mat3& T_cov = Mat3::Zero());

/// The set in the robot base frame (through its sensor_pose); already-"base" sets are returned as is.
FeatureSet toBaseFrame(const FeatureSet& set);

/// True when a corner's orientation variance says "unknown" (sonar corners, docs/algorithms.md §17.3).
inline bool cornerOrientationUnknown(const Mat3& cov) { return !(cov(2, 2) < 0.1 * kUnknownAngleVariance); }

}  // namespace polarslam
