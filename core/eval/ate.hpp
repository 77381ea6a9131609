#pragma once
// Absolute trajectory error (ATE) of an estimated trajectory against ground truth, both raw (the
// two trajectories are taken to share a frame) and after the least-squares rigid SE(2)
// alignment of the estimate onto the ground truth (closed-form 2D Umeyama/Horn, no scale).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "eval/error_statistics.hpp"
#include "geometry/features.hpp"

namespace polarslam {

struct AteOptions {
  /// Ground truth is interpolated between its samples on either side of an estimated pose's
  /// time when both are within this, else the nearest sample within it is used; else the
  /// estimated pose is unmatched.
  int64_t max_time_difference_us = 100000;
};

struct AteResult {
  size_t estimated = 0;   ///< poses in the estimate
  size_t matched = 0;     ///< estimated poses with ground truth at their time
  size_t unmatched = 0;
  ErrorStatistics raw_translation;       ///< m, |p̂ − p|
  ErrorStatistics raw_rotation_deg;      ///< deg, |wrap(θ̂ − θ)|
  ErrorStatistics aligned_translation;   ///< m, after alignment
  ErrorStatistics aligned_rotation_deg;  ///< deg, after alignment
  Pose2 alignment;  ///< maps the estimate's frame into the ground truth's: p_gt ≈ alignment ⊕ p̂
};

/// The rigid transform T minimising Σ|target_i − T(source_i)|² (needs ≥ 1 pair; with one pair,
/// or all points equal, the rotation is undetermined and taken as 0).
Pose2 alignRigid2d(const std::vector<Vec2>& source, const std::vector<Vec2>& target);

AteResult evaluateAte(const std::vector<PoseStamped>& estimate, const std::vector<PoseStamped>& ground_truth,
                      const AteOptions& options = {});

/// `poses` re-expressed in the frame of the first one: the robot's starting frame, which is the
/// map frame of every estimator (ground truth is compared there).
std::vector<PoseStamped> inStartFrame(std::vector<PoseStamped> poses);

}  // namespace polarslam
