#pragma once
// Feature-based EKF SLAM (thesis §3.5–§3.6) over an odometry stream and a stream of feature sets
// in the robot base frame (FEATURES: laser, sonar or fused lines, right-angle corners, points).
//
//  - prediction: the odometry error model of docs/algorithms.md §17.6 (odometry/odometry_model.hpp);
//    odometry readings are cut at each feature set's time stamp by interpolation;
//  - observation models and Jacobians: App. B as corrected in docs/algorithms.md §17.8 (slam/feature_models);
//  - association: gate + JCBB + ambiguity rejection (slam/association.hpp), after per-kind
//    compatibility: a line is only matched from the side it was first seen from (the two faces
//    of a thin wall are different surfaces) and within `max_line_extent_gap` of its observed
//    extent; corners need the same convexity; points and corners are only matched from
//    directions within `max_view_change` of the arc of directions they were seen from (a small
//    feature on the far side of a thin wall, centimetres away, is another target);
//  - new features: an observation that matches nothing and lies outside the looser
//    `new_feature_probability` gate of every map feature starts a *tentative* feature outside the
//    filter; after `confirm_observations` observations (each within `tentative_timeout_s` of the
//    last) it enters the state, initialised from the latest observation through g() with
//    P_yy = G_x·P_vv·G_xᵀ + G_z·R·G_zᵀ. Spurious returns never reach the filter;
//  - line endpoints: kept outside the filter as an extent [t_min, t_max] along each map line
//    (docs/algorithms.md §17.9), grown by projecting every matched segment onto it;
//  - scan anchors: for each requested laser scan time, the map features near the robot seen from
//    the posterior pose at that time, with the covariance H·P·Hᵀ of that relative view (§3.7.2).
//
// Input arrives in any interleaving; everything is processed in time order. A feature set is
// processed once odometry reaches its time stamp (or `latency_s` of stream time has passed), so
// feature sets may lag odometry by up to `latency_s`. With `feature_set_per_scan` (the laser feeds
// the feature stream), every scan announced by requestAnchors() has a feature set on its way:
// until it arrives no later odometry or anchors are processed, however far the stream it comes
// on lags (a slow or loaded machine), up to `max_feature_lag_s` for a stalled peer. Nothing here
// throws on bad input: it is counted in stats() and skipped.
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "odometry/odometry_model.hpp"
#include "slam/association.hpp"
#include "slam/ekf_state.hpp"
#include "slam/feature_map.hpp"

namespace polarslam {

struct FeatureSlamParams {
  /// Defaults match the simulated robot (config/robots/default.yaml: wheel base 0.5 m, per-wheel
  /// variance 2e-5 m²/m).
  OdometryModelParams odometry = defaultOdometry();
  AssociationParams association;
  double new_feature_probability = 0.9999;  ///< within this gate of a map feature: never a new one
  double tentative_gate_probability = 0.999;
  int confirm_observations = 3;
  double tentative_timeout_s = 2.0;
  double min_line_distance = 0.05;    ///< m: lines closer to the robot are skipped (flip, §17.8)
  double min_corner_range = 0.05;     ///< m
  double max_line_extent_gap = 2.5;   ///< m: an observed segment this far beyond a map line's extent is another wall
  /// rad: a point or corner seen from a direction this far outside the arc of directions it has
  /// been seen from is another target (e.g. the far side of a thin wall)
  double max_view_change = deg2rad(60.0);
  double observation_cov_scale = 1.0; ///< multiplies every measurement covariance
  double anchor_radius = 5.0;         ///< m
  int max_anchors = 24;
  double latency_s = 0.3;             ///< how long odometry waits for feature sets of its time
  /// Every laser scan (requestAnchors) is followed by a feature set of its time stamp (the fused
  /// stream with the laser in use): odometry and anchors wait for it, not only `latency_s`.
  bool feature_set_per_scan = false;
  double max_feature_lag_s = 5.0;     ///< s of stream time to wait for an announced scan's feature set
  /// Allowance for the robot's relative drift between two observations of a tentative feature
  /// (x, y, θ std): tentatives are matched on their own, not through the filter.
  Vec3 tentative_pose_sigma = Vec3(0.05, 0.05, 0.02);

  static OdometryModelParams defaultOdometry();
};

/// One robot-frame measurement as the filter uses it.
struct Observation {
  MapFeatureKind kind = MapFeatureKind::Line;
  Vec3 z = Vec3::Zero();   ///< line (α, d), corner (φ, r, γ), point (x, y)
  Mat3 R = Mat3::Zero();
  int dim = 2;             ///< 3 for a corner with a known orientation
  bool convex = false;
  FeatureSource source = FeatureSource::Laser;
  Vec2 endpoint_a = Vec2::Zero(), endpoint_b = Vec2::Zero();  ///< lines, robot frame
};

/// Observations from a base-frame feature set; unusable features are counted in `rejected`.
std::vector<Observation> observationsFrom(const FeatureSet& base, const FeatureSlamParams& params, int* rejected);

struct FeatureSlamStats {
  long odometry = 0, feature_sets = 0, observations = 0;
  long paired = 0, ambiguous = 0, near_existing = 0;  ///< per observation
  long tentative_started = 0, promoted = 0, tentative_expired = 0;
  long rejected_odometry = 0, rejected_sets = 0, rejected_features = 0, failed_updates = 0;
  long jcbb_budget_exhausted = 0;
  long gave_up_waiting = 0;  ///< inputs processed without an announced scan's feature set (max_feature_lag_s)
  std::map<std::string, long> reject_reasons;
  double update_seconds = 0.0;  ///< CPU-independent wall time spent in association + update
  long updates = 0;
};

class FeatureSlam {
 public:
  explicit FeatureSlam(FeatureSlamParams params = {});

  /// Each returns an empty string when accepted, else why the input was rejected.
  std::string addOdometry(const OdometryReading& reading);
  std::string addFeatures(const FeatureSet& features);
  /// Asks for the scan anchors at a laser scan's time stamp.
  std::string requestAnchors(int64_t utime);

  /// Processes everything still queued (end of a log).
  void flush();

  /// Filter poses at the processed odometry time stamps since the last call.
  std::vector<PoseStamped> takePoses();
  /// Scan anchors produced since the last call.
  std::vector<ScanAnchors> takeAnchors();

  /// The latest pose: the filter's, moved on by odometry not yet processed.
  PoseStamped currentPose() const;
  /// False until the first odometry or features: currentPose() has no time yet.
  bool started() const { return filter_time_ != std::numeric_limits<int64_t>::min(); }
  /// The confirmed map (lines normalised to d ≥ 0) with the filter's robot pose.
  FeatureMap map() const;
  /// Map features near the robot as seen from the current filter pose.
  ScanAnchors anchorsNow(int64_t utime) const;

  const EkfState& state() const { return state_; }
  const FeatureSlamStats& stats() const { return stats_; }
  size_t tentativeCount() const { return tentatives_.size(); }
  int64_t filterTime() const { return filter_time_; }
  /// (feature set utime, map feature id) of every match since the last call.
  std::vector<std::pair<int64_t, int64_t>> takeMatches();

 private:
  struct FeatureInfo {
    int64_t id = 0;
    MapFeatureKind kind = MapFeatureKind::Line;
    int observations = 0;
    int64_t first_utime = 0, last_utime = 0;
    bool convex = false;
    double side = 1.0;                       ///< lines: the flip sign s seen at initialisation
    double t_min = 0.0, t_max = 0.0;         ///< lines: extent along the map line direction
    /// Points and corners: directions (map frame, feature → robot) they were seen from, as an
    /// arc [view_lo, view_hi] relative to view_ref.
    double view_ref = 0.0, view_lo = 0.0, view_hi = 0.0;
  };
  struct Tentative {
    FeatureInfo info;
    Vec3 y = Vec3::Zero();
    Mat3 P = Mat3::Zero();
    bool gamma_known = false;
  };

  void reject(long& counter, const std::string& reason);
  void process(bool flushing);
  void advanceTo(int64_t t);
  void predictTo(const OdometryReading& reading);
  void processFeatures(const FeatureSet& set);
  void emitAnchors(int64_t utime);

  std::optional<LinearizedObservation> linearize(int feature, const Observation& obs, double* side) const;
  bool compatible(const FeatureInfo& info, const Observation& obs, double side, const Vec2& position) const;
  /// Direction from a feature at `position` to the robot, relative to the feature's reference.
  double viewAngle(const FeatureInfo& info, const Vec2& position) const;
  static void widenView(FeatureInfo& info, double relative);
  void growExtent(FeatureInfo& info, const Vec2& map_line, const Observation& obs, const Pose2& pose) const;
  void handleUnmatched(const std::vector<const Observation*>& unmatched, int64_t utime);
  void promote(Tentative& t, const Observation& obs);
  void expireTentatives(int64_t utime);

  FeatureSlamParams params_;
  EkfState state_;
  std::vector<FeatureInfo> info_;  ///< parallel to state_.features()
  std::vector<Tentative> tentatives_;
  std::deque<OdometryReading> odometry_queue_;
  std::deque<FeatureSet> feature_queue_;
  std::deque<int64_t> anchor_queue_;
  std::optional<OdometryReading> last_reading_;  ///< the reading the filter pose corresponds to
  int64_t last_odometry_utime_ = std::numeric_limits<int64_t>::min();
  int64_t last_feature_utime_ = std::numeric_limits<int64_t>::min();
  int64_t last_scan_utime_ = std::numeric_limits<int64_t>::min();  ///< latest requestAnchors() time
  int64_t stream_time_ = std::numeric_limits<int64_t>::min();
  int64_t filter_time_ = std::numeric_limits<int64_t>::min();
  int64_t next_id_ = 1;
  std::vector<PoseStamped> poses_;
  std::vector<ScanAnchors> anchors_;
  std::vector<std::pair<int64_t, int64_t>> matches_;
  FeatureSlamStats stats_;
};

}  // namespace polarslam
