#pragma once
// Laser and advanced-sonar fusion (thesis §3.3; docs/algorithms.md §17.1, §17.4, §17.5).
//
// Fusion rule (§3.3.2, sourced in words): laser and sonar measurements of the same line or
// right-angle corner, in the robot base frame at one time stamp, are averaged with their
// information matrices as weights, P = (P₁⁻¹ + P₂⁻¹)⁻¹, z = P(P₁⁻¹z₁ + P₂⁻¹z₂), angles wrapped.
// "The same" means: the innovation passes a χ² gate (and, for a sonar plane, its normal foot lies
// on the laser segment, since a specular echo only returns from there). A sonar corner has no
// orientation, so it contributes information on the apex only. Unmatched measurements pass
// through alone.
//
// FeatureFusion turns the LASER_FEATURES, SONAR, LASER and ODOMETRY streams into one FEATURES
// stream in the base frame: each laser feature set waits sonar_wait_s of stream time for the
// sonar cycles around its time (stream time alone decides, so that the order in which the
// streams happen to arrive changes nothing; a sonar cycle near a raw scan already received waits
// for that scan's laser set, however late the features stage is), the sonar features are moved to the laser scan's time with the
// odometry (and its covariance), checked against the raw laser scan (sonar_selection.hpp), and
// fused. Sonar cycles with no laser scan near them are passed on alone, so sonar information is
// never lost; output is always in time order.
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_history.hpp"
#include "sonar/sonar_features.hpp"
#include "sonar/sonar_selection.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

// ---- Fusion math ---------------------------------------------------------------------------------

/// Mahalanobis distance² between two lines (same frame), α wrapped.
double lineDistance2(const LineFeature& a, const LineFeature& b);
/// Information-weighted average of two lines; source Fused, the first one's segment.
LineFeature fuseLines(const LineFeature& a, const LineFeature& b);

/// Mahalanobis distance² between two corners over the apex, plus γ when both know it; `dof`
/// receives 2 or 3.
double cornerDistance2(const CornerFeature& a, const CornerFeature& b, int* dof = nullptr);
/// Information-weighted average of two corners; a corner whose γ is unknown adds no γ information.
CornerFeature fuseCorners(const CornerFeature& a, const CornerFeature& b);

/// True when a sonar plane's normal foot lies on the laser segment, within `tolerance` beyond its ends.
bool footOnSegment(const LineFeature& sonar_plane, const LineFeature& laser_line, double tolerance);

struct FusionCounts {
  int fused_lines = 0, fused_corners = 0;
  int sonar_lines_alone = 0, sonar_corners_alone = 0, sonar_points = 0;
  int ambiguous = 0;  ///< sonar measurements that gated with more than one laser feature
};

struct FusionMathParams {
  double gate_probability = 0.99;
  double foot_tolerance = 0.3;  ///< m
};

/// Fuses sonar features into laser features (both base frame, same time); sonar features that
/// match nothing — or more than one thing — are appended alone.
FeatureSet fuseFeatureSets(const FeatureSet& laser_base, const FeatureSet& sonar_base, const FusionMathParams& params,
                           FusionCounts* counts = nullptr);

// ---- Stream fusion -------------------------------------------------------------------------------

struct FeatureFusionParams {
  bool use_laser = true;
  bool use_sonar = true;
  bool laser_aided_selection = true;
  SonarFeatureParams sonar;
  SonarSelectionParams selection;
  FusionMathParams fusion;
  double max_sonar_offset_s = 0.06;  ///< sonar cycles this close to a laser scan are fused with it
  double sonar_wait_s = 0.15;        ///< a laser set waits this long (stream time) for sonar cycles
  double laser_wait_s = 0.3;         ///< a sonar cycle waits this long for a laser set
  /// A sonar cycle near a raw scan already received waits for that scan's laser set however late
  /// it comes (a slow features stage), up to this long (stream time) for a stalled one.
  double max_laser_lag_s = 5.0;
  double unknown_speed = 0.6;        ///< m/s: bound on motion between stamps when odometry is missing
  double unknown_turn_rate = 1.0;    ///< rad/s
  OdometryModelParams odometry;
};

struct FeatureFusionStats {
  long laser_sets = 0, sonar_scans = 0, output_sets = 0;
  long late = 0;                 ///< inputs older than what was already emitted
  long uncompensated = 0;        ///< sonar cycles moved without odometry (motion bound used)
  long missing_laser_sets = 0;   ///< raw scans whose laser set had not come after max_laser_lag_s (sonar waits on them)
  SonarFeatureCounts sonar;
  SelectionCounts selection;
  FusionCounts fusion;
};

class FeatureFusion {
 public:
  explicit FeatureFusion(FeatureFusionParams params = {});

  /// Each returns false when the input is rejected (non-finite, late or out of order).
  bool addOdometry(const OdometryReading& reading);
  bool addLaserScan(const LaserScan& scan);
  bool addLaserFeatures(const FeatureSet& laser_features);
  bool addSonar(const SonarScan& scan);

  /// Feature sets (frame "base") ready so far, oldest first; removes them.
  std::vector<FeatureSet> takeReady();
  /// Emits everything still pending (end of a log).
  void flush();

  const FeatureFusionStats& stats() const { return stats_; }
  const FeatureFusionParams& params() const { return params_; }

 private:
  void observeTime(int64_t utime);
  void process(bool flushing);
  void emitSonarAlone(const SonarScan& scan);
  void emitLaser(const FeatureSet& laser, const std::vector<SonarScan>& sonar);
  void emit(FeatureSet set);
  bool laserReady(const FeatureSet& laser) const;
  /// True while a raw scan within `until` still has its laser set to come.
  bool laserSetDue(int64_t until) const;
  /// Gives up on the laser sets of raw scans older than max_laser_lag_s (counted).
  void dropStalledLaserSets();
  /// Sonar features of a scan, in the base frame at time `utime`.
  FeatureSet sonarAt(const SonarScan& scan, int64_t utime);
  const LaserScan* rawScanAt(int64_t utime) const;

  FeatureFusionParams params_;
  OdometryHistory odometry_;
  std::deque<FeatureSet> pending_laser_;
  std::deque<SonarScan> pending_sonar_;
  std::deque<LaserScan> raw_scans_;  ///< normalised
  std::deque<int64_t> laser_sets_due_;  ///< raw scans received whose laser set has not come yet
  std::vector<FeatureSet> ready_;
  int64_t stream_time_ = std::numeric_limits<int64_t>::min();
  int64_t emitted_until_ = std::numeric_limits<int64_t>::min();
  int64_t output_seq_ = 0;
  FeatureFusionStats stats_;
};

}  // namespace polarslam
