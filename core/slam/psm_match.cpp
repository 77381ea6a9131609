#include "slam/psm_match.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

namespace polarslam {

Mat3 covarianceFloor(double sigma_xy, double sigma_theta) {
  return Vec3(sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_theta * sigma_theta).asDiagonal();
}

std::optional<PreparedScan> prepareMatchableScan(const LaserScan& scan, const PsmParams& params) {
  if (!validateScan(scan).empty()) return std::nullopt;
  try {
    PreparedScan prepared = prepareScan(scan, params);
    if (prepared.valid_count < params.min_valid_points) return std::nullopt;
    return prepared;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::optional<RobotFrameMatch> matchInRobotFrame(ScanMatcher& matcher, const PreparedScan& reference,
                                                 const Pose2& reference_mount, const PreparedScan& scan,
                                                 const Pose2& mount, const Pose2& guess, const PsmSlamParams& params,
                                                 bool wide) {
  const PsmParams saved = matcher.params();
  if (wide) {
    matcher.params().initial_search_window = params.loop_search_window;
    // A loop candidate's guess can be far off, and where only part of the scan associates on
    // the way, a look-alike place converges as readily as the right one: every step needs the
    // full support (simulated office, 300 seeds: 10 wrong loop edges instead of 5 otherwise).
    matcher.params().step_min_points_fraction = 1.0;
  }
  const Pose2 laser_guess = laserPoseInReferenceLaser(Pose2(), guess, reference_mount, mount);
  const MatchResult m = matcher.match(reference, scan, laser_guess, params.method);
  matcher.params() = saved;
  if (!m.ok() || (wide && !m.converged) || !finitePose(m.pose) || !m.cov.allFinite()) return std::nullopt;
  RobotFrameMatch match;
  match.z = robotMotionFromLaserMotion(m.pose, reference_mount, mount);
  match.R = params.match_cov_scale * robotMotionCovariance(m.pose, m.cov, reference_mount, mount) +
            covarianceFloor(params.min_match_sigma_xy, params.min_match_sigma_theta);
  match.error_index = m.error_index;
  match.overlap = static_cast<double>(m.valid_points) / std::max(1, std::min(reference.valid_count, scan.valid_count));
  return match;
}

double errorIndexAt(ScanMatcher& matcher, const PreparedScan& reference, const Pose2& reference_mount,
                    const PreparedScan& scan, const Pose2& mount, const Pose2& z) {
  MatchResult at;
  at.pose = laserPoseInReferenceLaser(Pose2(), z, reference_mount, mount);
  matcher.estimateCovariance(reference, scan, at);
  return at.error_index;
}

bool predictionMisfits(ScanMatcher& matcher, const PreparedScan& reference, const Pose2& reference_mount,
                       const PreparedScan& scan, const Pose2& mount, const Pose2& predicted, double match_error_index,
                       const PsmSlamParams& params) {
  return errorIndexAt(matcher, reference, reference_mount, scan, mount, predicted) >
         params.odometry_fault_fit_ratio * match_error_index;
}

}  // namespace polarslam
