#pragma once
// Localisation in a stored PSM SLAM map (issue 15; docs/maps.md): the map's reference scans stay
// fixed, nothing is added to them. Per scan the robot pose is predicted with odometry (the same
// model as PSM SLAM's filter), matched by PSM against the nearest reference scans, and updated
// with the best good match that passes the χ² gate: a 3-state EKF whose map is known.
//
// New ground. A scan that matches no reference scan of the map is matched with the last scan
// that did (a local reference, renewed as the robot moves on, never added to the map): on
// ground the map does not hold the pose goes on by scan matching, its covariance growing, and
// tracking picks the map up again when the robot comes back. Only a scan that matches neither
// counts towards being lost: a kidnapped robot's view does not continue the one before. New
// ground does not lie where the map's reference scans are: `lost_near_map_after_scans` scans in a
// row near them without a match with the map also lose the robot (carried along a look-alike
// corridor, its view may continue the one before).
//
// Global localisation. When the start is unknown, or the robot has been lost for
// `lost_after_scans` scans in a row (kidnapped, or the odometry failed), every robot pose near
// the map's reference poses, at every heading, is scored by how well the scan, and the scans
// seen since the loss placed by dead reckoning, lie on the map (correlative_search.hpp); the
// search is repeated each time the robot has moved on by `global_search_spacing` or turned by
// `global_search_turn`. The best pose is taken only when no other place (one seeing through no
// mapped wall) fits about as well (the loop-closure ambiguity rule), PSM refines it with the
// nearest reference scans alike, and the next search agrees with it after the odometry in
// between: a look-alike corridor gives no hit rather than a wrong one. Until then
// the poses are odometry only and flagged as such; once a fix is found, the final trajectory
// re-places the scans since the loss by odometry from the fix.
//
//   MapLocalizer localizer(references, params);
//   localizer.addOdometry(reading);
//   MapLocalizationResult r = localizer.addScan(scan);   // r.localized, r.pose
#include <cstdint>
#include <optional>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_model.hpp"
#include "scanmatch/prepared_scan.hpp"
#include "scanmatch/scan_matcher.hpp"
#include "slam/correlative_search.hpp"
#include "slam/map_fit_field.hpp"
#include "slam/psm_slam_params.hpp"

namespace polarslam {

/// One reference scan of a map and the robot pose it was taken from, in the map frame.
struct MapReference {
  int64_t id = 0;
  Pose2 pose;
  LaserScan scan;
};

struct MapLocalizationResult {
  PoseStamped pose;             ///< robot pose in the map frame (odometry only unless localized)
  bool usable = false;          ///< the scan could be matched at all
  bool localized = false;       ///< the pose is tied to the map (tracking)
  bool matched = false;         ///< a match with the map updated the pose on this scan
  bool found = false;           ///< the global search fixed the pose on this scan
  int64_t reference = -1;       ///< the reference scan of the match, if any
};

struct MapLocalizerStats {
  size_t scans = 0;
  size_t unusable_scans = 0;
  size_t matched_scans = 0;        ///< tracking: a match updated the pose
  size_t odometry_only_scans = 0;  ///< not localized: pose from odometry alone
  size_t match_failures = 0;       ///< tracking: no good match with any candidate
  size_t new_ground_scans = 0;     ///< tracking: no map match, placed by the local reference
  size_t off_map_timeouts = 0;     ///< on new ground until the pose was too uncertain: lost
  size_t gate_rejections = 0;      ///< tracking: good matches outside the χ² gate
  size_t odometry_faults = 0;      ///< tracking: gated-out matches taken as odometry faults
  size_t global_searches = 0;
  size_t global_nodes = 0;         ///< poses and pose ranges the global searches scored
  size_t global_ambiguous = 0;     ///< searches whose best pose had a look-alike elsewhere
  size_t global_unrefined = 0;     ///< best poses PSM could not refine (the search's pose stood)
  size_t global_see_through = 0;   ///< hits refused for seeing through mapped walls
  size_t global_unsupported = 0;   ///< best poses whose PSM refinements disagreed
  size_t global_unconfirmed = 0;   ///< unambiguous hits the next search did not agree with
  size_t doubt_searches = 0;       ///< global searches while tracked, the fit having dropped
  size_t doubts = 0;               ///< ... that found the robot elsewhere: tracking lost
  size_t fixes = 0;                ///< global searches that localized the robot
  size_t losses = 0;               ///< times tracking was lost (kidnapping, odometry failure)
  int64_t first_fix_scan = -1;     ///< scan index (0-based) of the first fix
  double doubt_seconds = 0.0;      ///< wall-clock time in doubt searches
  double search_seconds = 0.0;     ///< ... in global searches while lost
};

class MapLocalizer {
 public:
  /// Throws std::invalid_argument when no reference scan is usable, std::length_error when the map
  /// spreads too far for the global search's grids (CorrelativeSearchParams::max_cells).
  MapLocalizer(const std::vector<MapReference>& references, PsmSlamParams params);

  /// A known start: tracking begins at `pose` (map frame) with covariance `cov`.
  void setInitialPose(const Pose2& pose, const Mat3& cov);
  /// The robot is lost at `pose` (dead reckoning from here on; time `utime`): the global search
  /// takes over. Used when something else tracked it meanwhile (map_localization_estimator.hpp);
  /// the odometry received since its last scan is dropped, the motion up to `pose` is in it.
  void searchFrom(const Pose2& pose, int64_t utime);
  /// Doubt, while the robot is tracked (here or by temporary mapping) at `tracked` (map frame) on
  /// this scan: true when it is elsewhere. Where the tracked pose is near the map's reference
  /// scans but fits less than doubt_max_fit of the scan's readings to it, the scans seen since
  /// the fit dropped, at their tracked poses, are searched for globally (every
  /// global_search_spacing); an unambiguous place away from the tracked pose that they fit
  /// markedly better (global_misfit_ratio) means the robot was carried there: lose it, and let
  /// the global search confirm where.
  bool doubt(const LaserScan& scan, const Pose2& tracked);
  /// Cumulative odometry; bad readings are counted by the integrator and ignored.
  void addOdometry(const OdometryReading& reading);
  /// One laser scan; never throws for bad content.
  MapLocalizationResult addScan(const LaserScan& scan);

  /// One pose per scan as published at scan time.
  const std::vector<PoseStamped>& onlineTrajectory() const { return online_; }
  /// One pose per scan, the odometry-only stretches re-placed from the fix that ended them.
  std::vector<PoseStamped> trajectory() const;
  /// Per scan: whether its online pose was tied to the map.
  const std::vector<bool>& localizedFlags() const { return localized_flags_; }
  const MapLocalizerStats& stats() const { return stats_; }
  bool localized() const { return localized_; }
  size_t referenceCount() const { return references_.size(); }

 private:
  struct Reference {
    int64_t id = 0;
    Pose2 pose;
    Pose2 laser_mount;
    PreparedScan scan;
  };
  /// A match of the current scan with one reference, as a robot pose in the map frame.
  struct Fix {
    size_t reference = 0;
    Pose2 pose;
    Mat3 cov = Mat3::Zero();
    double error_index = 0.0;
    double overlap = 0.0;
    double fit = 0.0;     ///< of the whole scan to the map at `pose` (global search)
    double score = 0.0;   ///< of the searched points at the correlative search's pose
  };
  /// The last scan tied to the map (or to such a scan), at its pose and covariance: new ground
  /// is tracked against it.
  struct LocalReference {
    Pose2 pose;
    Mat3 cov = Mat3::Zero();
    Pose2 laser_mount;
    PreparedScan scan;
  };
  /// A scan seen while lost: a few of its points (robot frame) and its dead-reckoning pose.
  struct SearchedScan {
    Pose2 pose;
    std::vector<Vec2> points;
  };
  struct Hypothesis {
    Pose2 pose;           ///< the hit's robot pose
    Pose2 odometry_pose;  ///< the dead-reckoning pose at that scan
  };
  /// The odometry-only stretch a fix ended: scans [first, last) re-placed from scan `last`.
  struct Stretch {
    size_t first = 0, last = 0;
  };

  void predictTo(int64_t utime);
  std::optional<Fix> match(size_t reference, const PreparedScan& scan, const Pose2& mount, const Pose2& relative_guess,
                           bool wide);
  bool goodFix(const Fix& fix, bool global) const;
  /// The reference scans within track_radius and track_heading of `pose`, nearest first, at most `count`.
  std::vector<size_t> nearestReferences(const Pose2& pose, size_t count) const;
  enum class Tracked { Matched, NewGround, Failed };
  /// Tracking: matches the nearest references and applies the best good match; else new ground.
  Tracked track(const PreparedScan& scan, const Pose2& mount, MapLocalizationResult& result);
  /// Places the scan by a match with the local reference. True if applied.
  bool trackNewGround(const PreparedScan& scan, const Pose2& mount);
  void newLocalReference(const PreparedScan& scan, const Pose2& mount);
  /// While lost: whether the robot has moved on enough since the last global search.
  bool searchDue(const Pose2& predicted) const;
  void searchAndConfirm(const LaserScan& raw, const PreparedScan& scan, const Pose2& predicted,
                        MapLocalizationResult& result);
  /// Applies a good match of `scan` (laser at `mount`) with the map; false if gated out.
  bool applyFix(const Fix& fix, const PreparedScan& scan, const Pose2& mount);
  /// Where the robot would be had it kept the motion between the last two scans (real odometry
  /// goes stale and catches up in one jump; PSM SLAM matches from this prior too).
  Pose2 constantVelocityPose() const { return last_scan_pose_ * last_scan_motion_; }
  /// Whether a gated-out match (pose `measured`, error index `match_error_index`, of `scan` against
  /// `reference` taken at `reference_pose`) is an odometry fault: it lies within an odometry fault
  /// of the prediction or of the previous motion kept up, and the prediction fits the scan
  /// markedly worse (odometry_fault_fit_ratio). Then it is taken, not rejected.
  bool odometryFaultExplains(const Pose2& measured, double match_error_index, const PreparedScan& reference,
                             const Pose2& reference_pose, const Pose2& reference_mount, const PreparedScan& scan,
                             const Pose2& mount);
  bool withinGate(const Vec3& innovation, const Mat3& innovation_cov) const;
  /// Global search: the unambiguous best hit of `points` (robot frame, `raw` the current scan), if
  /// any; `current` is where the robot is thought to be now (tracked, or dead reckoning).
  std::optional<Fix> searchGlobally(const LaserScan& raw, const PreparedScan& scan, const std::vector<Vec2>& points,
                                    const Pose2& current);
  /// The global search's query: places from global_min_score, rivals within global_score_margin.
  CorrelativeQuery globalQuery() const;
  /// Adds a place a search found (they come best first) to `rivals` if it could be where the robot
  /// is: it sends at most `see_through_limit` of `raw`'s rays through mapped walls, and misfits at
  /// most global_misfit_ratio times the first of them.
  void admitRival(const LaserScan& raw, const CorrelativeHit& place, double see_through_limit,
                  std::vector<CorrelativeHit>& rivals);
  /// The one of `places` refined and checked, if there is exactly one and it holds.
  std::optional<Fix> fixAmong(const LaserScan& raw, const PreparedScan& scan, const std::vector<CorrelativeHit>& places);
  /// The fraction of `raw`'s rays a place may send through mapped walls: global_max_see_through, or
  /// half of what `current` sends through if more.
  double seeThroughLimit(const LaserScan& raw, const Pose2& current) const;
  /// The points of `scans` in `pose`'s robot frame: at most global_points of them.
  std::vector<Vec2> sequencePoints(const std::vector<SearchedScan>& scans, const Pose2& pose) const;
  /// Adds `latest` to `scans` and drops those beyond global_sequence_distance of it, or more than
  /// kMaxSequenceScans back (a robot standing still): the list stays bounded however long it is lost.
  void keepRecent(std::vector<SearchedScan>& scans, SearchedScan latest) const;
  static constexpr size_t kMaxSequenceScans = 400;
  /// The doubt search proper: a place elsewhere explains the doubted scans markedly better.
  bool foundElsewhere(const LaserScan& scan, const PreparedScan& prepared, const Pose2& tracked);
  /// The window around the search's pose in which the current scan alone is placed.
  static constexpr double kRefineTranslation = 0.3;  ///< m
  static constexpr double kRefineRotation = deg2rad(8.0);
  /// The best hit refined by PSM with the reference scans nearest to it, unless they disagree.
  std::optional<Fix> refineGlobalHit(const Pose2& hit, double score, const PreparedScan& scan, const Pose2& mount);
  /// The reference scan nearest to `pose`'s position.
  size_t nearestReference(const Pose2& pose) const;
  /// At most global_points of the scan's readings within max_range, in the robot frame.
  std::vector<Vec2> searchPoints(const LaserScan& raw) const;
  void lose();
  /// m travelled from the first of `scans` to the last, pose to pose.
  static double pathLength(const std::vector<SearchedScan>& scans);
  void record(const MapLocalizationResult& result);

  PsmSlamParams params_;
  MapLocalizationParams options_;
  ScanMatcher matcher_;
  std::vector<Reference> references_;
  std::optional<MapFitField> field_;
  std::optional<CorrelativeMapSearch> correlative_;
  OdometryIntegrator odometry_;
  bool have_odometry_ = false;
  Pose2 pending_motion_;
  Mat3 pending_cov_ = Mat3::Zero();
  std::optional<int64_t> last_utime_;

  Pose2 last_scan_pose_, last_scan_motion_;
  Pose2 pose_;                  ///< map frame when localized_, else dead reckoning since the loss
  Mat3 cov_ = Mat3::Zero();
  bool localized_ = false;
  int failures_in_a_row_ = 0;
  int unmatched_near_map_ = 0;  ///< scans in a row with reference scans near but no map match
  std::optional<Hypothesis> hypothesis_;
  std::optional<LocalReference> local_reference_;
  std::optional<Pose2> last_search_at_;  ///< dead-reckoning pose of the last global search
  std::vector<SearchedScan> searched_;   ///< the scans since the loss, newest last
  std::vector<SearchedScan> doubted_;    ///< tracked scans since the fit dropped, at their tracked poses
  std::optional<Pose2> last_doubt_at_;   ///< tracked pose of the last doubt search
  std::optional<size_t> lost_since_;  ///< first scan of the current odometry-only stretch

  std::vector<PoseStamped> online_;
  std::vector<bool> localized_flags_;
  std::vector<Pose2> dead_reckoning_;  ///< per scan: the odometry-only pose chain
  std::vector<Stretch> stretches_;
  MapLocalizerStats stats_;
};

}  // namespace polarslam
