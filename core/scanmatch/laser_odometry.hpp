#pragma once
// Laser odometry by scan matching against a keyframe (docs/algorithms.md, appendix "how the original PSM
// behaves on real logs"): each scan is matched to the last keyframe with the wheel-odometry
// motion as the prior; a new keyframe is taken after enough motion. Matching against a keyframe
// instead of the previous scan stops per-match jitter from accumulating, and when odometry and
// the match agree that the robot stands still the pose is held. The polarslam-psm process and
// `polarslam run --pipeline psm` both run this class.
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "scanmatch/scan_matcher.hpp"

namespace polarslam {

struct LaserOdometryParams {
  MatchMethod method = MatchMethod::Psm;
  double keyframe_distance = 0.10;        ///< m of motion since the keyframe that starts a new one
  double keyframe_angle = deg2rad(5.0);
  /// A new keyframe also when the match kept fewer than this share of the keyframe's readings.
  double keyframe_min_overlap = 0.5;
  /// Odometry motion since the previous scan below these counts as standing still ...
  double still_odometry_translation = 0.001;
  double still_odometry_rotation = deg2rad(0.05);
  /// ... and the pose is held if the match also moved less than these since the previous scan.
  double still_match_translation = 0.01;
  double still_match_rotation = deg2rad(0.3);
  /// Odometry readings farther than this from a scan (s) are not used as its prior.
  double max_odometry_gap = 1.0;
  /// Relative-motion standard deviation used when a match fails and the prior stands in:
  /// a floor plus a fraction of the motion.
  double fallback_sigma_xy = 0.05, fallback_sigma_theta = deg2rad(2.0), fallback_fraction = 0.2;
};

struct LaserOdometryUpdate {
  int64_t utime = 0;
  Pose2 pose;                 ///< robot base in the odometry frame (the pose of the first scan = origin)
  Mat3 cov = Mat3::Zero();
  bool matched = false;       ///< a match was attempted (false for the first scan)
  MatchResult match;          ///< current laser pose in the keyframe laser frame
  int64_t ref_utime = 0;      ///< keyframe the scan was matched against
  double match_time_us = 0.0; ///< thread CPU time of preparing the scan and matching
  bool held = false;          ///< standing still: the previous pose was kept
  bool new_keyframe = false;
  bool prior_from_odometry = false;
};

class LaserOdometry {
 public:
  explicit LaserOdometry(LaserOdometryParams params = {}, PsmParams psm = {});

  /// Wheel odometry, used as the prior between keyframe and scan (interpolated at scan times).
  void addOdometry(const OdometryReading& odometry);
  /// Processes one scan; the scan must pass validateScan() (otherwise std::invalid_argument).
  LaserOdometryUpdate addScan(const LaserScan& scan);

  const std::vector<PoseStamped>& trajectory() const { return trajectory_; }
  const LaserOdometryParams& params() const { return params_; }
  int64_t scans() const { return scans_; }
  int64_t failedMatches() const { return failed_; }
  int64_t keyframes() const { return keyframes_; }
  int64_t heldScans() const { return held_; }

 private:
  struct Keyframe {
    PreparedScan scan;
    Pose2 mount;
    Pose2 pose;          ///< robot pose in the odometry frame
    Mat3 cov = Mat3::Zero();
    int64_t utime = 0;
    std::optional<Pose2> odometry;  ///< wheel odometry at the keyframe time, if known
  };

  std::optional<Pose2> odometryAt(int64_t utime) const;
  Pose2 priorMotion(int64_t utime, const std::optional<Pose2>& odometry_now, bool& from_odometry) const;
  Mat3 fallbackCovariance(const Pose2& motion) const;
  void makeKeyframe(PreparedScan&& scan, const LaserScan& raw, const Pose2& pose, const Mat3& cov,
                    const std::optional<Pose2>& odometry);

  LaserOdometryParams params_;
  ScanMatcher matcher_;
  std::deque<OdometryReading> odometry_;
  std::optional<Keyframe> keyframe_;
  // the previous scan's estimate, for the constant-velocity prior and the stillness test
  Pose2 last_pose_, last_motion_;
  Mat3 last_cov_ = Mat3::Zero();
  std::optional<Pose2> last_odometry_;
  int64_t last_utime_ = 0;
  std::vector<PoseStamped> trajectory_;
  int64_t scans_ = 0, failed_ = 0, keyframes_ = 0, held_ = 0;
};

/// Thread CPU time in microseconds (for per-match timing).
double threadCpuMicros();

}  // namespace polarslam
