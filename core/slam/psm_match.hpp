#pragma once
// One PSM match as PSM SLAM and the map localiser use it: the scan prepared once, matched against
// a reference scan from a guess of the robot pose, and the result expressed as robot motion with
// its covariance (match_cov_scale, plus the smallest covariance the filters accept).
#include <optional>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "scanmatch/prepared_scan.hpp"
#include "scanmatch/scan_matcher.hpp"
#include "slam/psm_slam_params.hpp"

namespace polarslam {

/// A robot-frame match: the robot pose in the reference scan's robot frame.
struct RobotFrameMatch {
  Pose2 z;
  Mat3 R = Mat3::Zero();
  double error_index = 0.0;
  double overlap = 0.0;  ///< associated bearings over the smaller of the two scans' usable readings
};

/// diag(σxy², σxy², σθ²).
Mat3 covarianceFloor(double sigma_xy, double sigma_theta);

/// The scan prepared for PSM, if it can be matched at all: valid (validateScan), preparable, and
/// with at least min_valid_points usable readings.
std::optional<PreparedScan> prepareMatchableScan(const LaserScan& scan, const PsmParams& params);

/// Matches `scan` (laser at `mount`) against `reference` (laser at `reference_mount`) from
/// `guess`, the robot pose in the reference's robot frame. `wide`: a loop-closure or global
/// match, with the matcher's first orientation window widened to loop_search_window and only a
/// converged result taken. Nothing when the match fails or is not finite.
std::optional<RobotFrameMatch> matchInRobotFrame(ScanMatcher& matcher, const PreparedScan& reference,
                                                 const Pose2& reference_mount, const PreparedScan& scan,
                                                 const Pose2& mount, const Pose2& guess, const PsmSlamParams& params,
                                                 bool wide);

/// Error index of `scan` fitted to `reference` at robot pose `z` (in the reference's robot frame),
/// without iterating: the mean |range residual| a match ending there would report.
double errorIndexAt(ScanMatcher& matcher, const PreparedScan& reference, const Pose2& reference_mount,
                    const PreparedScan& scan, const Pose2& mount, const Pose2& z);

/// Whether the predicted robot pose (`predicted`, in the reference's robot frame) fits `scan` to
/// `reference` markedly worse than a match of error index `match_error_index` does: its error
/// index (mean |range residual|, as a match ending there would report it) is more than
/// params.odometry_fault_fit_ratio times the match's. Only then is a match outside the gate an
/// odometry fault; otherwise the scans allow both poses and the odometry is believed.
bool predictionMisfits(ScanMatcher& matcher, const PreparedScan& reference, const Pose2& reference_mount,
                       const PreparedScan& scan, const Pose2& mount, const Pose2& predicted, double match_error_index,
                       const PsmSlamParams& params);

}  // namespace polarslam
