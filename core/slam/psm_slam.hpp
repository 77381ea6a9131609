#pragma once
// SLAM with Polar Scan Matching (thesis §4.5, docs/algorithms.md §18), plus global pose-graph optimisation.
//
//   PsmSlam slam(params);
//   slam.addOdometry(reading);            // any number, in time order
//   PsmSlamScanResult r = slam.addScan(scan);   // r.pose: robot pose in the map frame now
//   ...
//   slam.optimize();                      // at the end: global consistency
//   std::vector<PoseStamped> poses = slam.trajectory();   // one pose per scan
//
// Per scan: the filter (psm_slam_filter.hpp) predicts with the odometry accumulated since the
// previous scan; PSM matches the scan against the active reference scan from that prior; a
// good match (converged, small error index, enough overlap, inside the χ² gate) updates the
// filter, unless odometry and match agree the robot stands still, in which case the pose is held
// (PSM's per-match jitter would otherwise accumulate). A good match outside the gate that a
// faulty odometry step explains (a heading jump, stale odometry catching up) is applied after
// inflating the prior along the miss: real odometry, not the match, is what fails there. When
// the robot has moved too far from the reference, or the overlap drops, the filter's
// uncertainty selects nearby reference scans
// (a Mahalanobis neighbourhood); each is matched, gated against the prediction and, if it
// passes, applied. A close, well-overlapping one becomes the reference again; otherwise the
// scan becomes a new reference, tied to the previous one in the pose graph by the filter's
// relative pose (odometry and matches fused, so that a corridor's free direction keeps the
// odometry). Matches with old reference scans are loop closures: they add
// robust edges to the pose graph and trigger a Ceres optimisation whose poses go back into the
// filter. Every scan's pose is stored relative to its reference scan, so the whole trajectory
// follows the optimised graph.
#include <cstdint>
#include <future>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_model.hpp"
#include "scanmatch/prepared_scan.hpp"
#include "scanmatch/scan_matcher.hpp"
#include "slam/pose_graph.hpp"
#include "slam/psm_match.hpp"
#include "slam/psm_slam_filter.hpp"
#include "slam/psm_slam_params.hpp"

namespace polarslam {

/// The filter of a run resumed from a snapshot: the whole filter state, and which of its
/// keyframes are the skeleton kept for loop closure (the others are the recent window).
struct PsmSlamFilterSeed {
  PsmSlamFilterState filter;
  std::vector<int64_t> skeleton;
};

struct GraphRefinementSummary {
  size_t pairs = 0;          ///< pairs of reference scans matched
  size_t edges = 0;          ///< good matches added to the graph
  size_t poor = 0;           ///< failed, or error index or overlap too poor
  size_t disagreed = 0;      ///< good, but away from where the graph puts the pair
  double seconds = 0.0;      ///< matching, in the background and at the end
  size_t background_rounds = 0;  ///< rounds after loop closures (online) whose edges joined the graph
  double final_seconds = 0.0;    ///< the end of the run's refinement: optimisation and matching
  GraphRefinementSummary& operator+=(const GraphRefinementSummary& other);
};

using NodePair = std::pair<int64_t, int64_t>;

/// A refinement round's input, copied out of PsmSlam so that it can be matched beside it: each
/// pair's relative pose as the graph had it, and the reference scans the pairs use.
struct RefinementScan {
  PreparedScan scan;
  Pose2 mount;
};
struct RefinementPair {
  int64_t reference = 0, current = 0;
  Pose2 guess;  ///< current in the reference's robot frame, from the graph
};
struct RefinementJob {
  std::vector<RefinementPair> pairs;
  std::map<int64_t, RefinementScan> scans;
};
struct RefinementEdge {
  int64_t from = 0, to = 0;
  Pose2 z;
  Mat3 R;  ///< the match's own covariance (before its scan's share)
};
struct RefinementOutcome {
  std::vector<RefinementEdge> edges;
  GraphRefinementSummary counts;
};
/// Matches each pair of `job` (a good match that agrees with the graph becomes an edge). Touches
/// nothing but its arguments: safe on another thread.
RefinementOutcome matchRefinementPairs(const RefinementJob& job, const PsmSlamParams& params);

struct PsmSlamStats {
  size_t scans = 0;
  size_t unusable_scans = 0;       ///< malformed, or too few usable readings to match
  size_t tracked_scans = 0;        ///< matched against the reference and applied
  size_t held_scans = 0;           ///< stationary: pose held
  size_t match_failures = 0;       ///< PSM failed or the match quality was too low
  size_t gate_rejections = 0;      ///< tracking matches outside the χ² gate
  size_t keyframes = 0;
  // Why a new reference was sought: no good match, moved too far, turned too far, overlap dropped.
  size_t references_lost = 0, references_too_far = 0, references_turned = 0, references_overlap = 0;
  size_t reference_reuses = 0;     ///< an existing reference scan taken up again
  size_t candidate_matches = 0;    ///< matches tried against candidate reference scans
  size_t loop_closures = 0;        ///< accepted matches with old reference scans
  size_t map_candidate_matches = 0;  ///< continuing a map: matches tried with its reference scans
  size_t map_loop_closures = 0;      ///< ... and accepted
  size_t loop_failed_matches = 0;  ///< old candidates PSM did not converge on
  size_t loop_poor_matches = 0;    ///< ... converged, but error index or overlap too poor
  size_t loop_ambiguous = 0;       ///< ... good, but another start in the prior found an equally good place
  size_t loop_gate_rejections = 0; ///< ... good, but outside the χ² gate of the prediction
  size_t loop_unconfirmed = 0;     ///< ... good, but a wide prior and no second closure agreeing (yet)
  size_t loop_refuted = 0;         ///< ... good, but a neighbouring reference scan matched elsewhere
  size_t loop_unverified = 0;      ///< ... good, but no neighbour matched and the prior is wider than a loop search
  size_t loop_unfiltered_refuted = 0;  ///< ... good, but the scans without the median filter fit elsewhere
  size_t optimizations = 0;
  size_t rejected_loop_edges = 0;  ///< loop and refinement edges the optimiser found inconsistent
  double optimization_seconds = 0.0;
  double last_optimization_seconds = 0.0;
  size_t odometry_rejected = 0;
  size_t odometry_faults = 0;      ///< scans whose odometry step disagreed with a better match
  size_t filter_flushes = 0;
};

/// What one scan did.
struct PsmSlamScanResult {
  PoseStamped pose;            ///< robot pose in the map frame after this scan
  AnchoredPose anchor;         ///< the same pose relative to its reference scan (graph node)
  bool usable = false;
  bool tracked = false;
  bool held = false;
  bool new_keyframe = false;
  bool loop_closed = false;
  bool optimized = false;
  /// A match with one of a continued map's reference scans updated the pose on this scan.
  bool map_matched = false;
};

class PsmSlam {
 public:
  explicit PsmSlam(PsmSlamParams params = {});

  /// Continues a saved map (call before any message): its pose graph and its reference scans
  /// (`references[i]` the scan of node i; node ids 0..n−1) become this run's first keyframes,
  /// and the robot starts at `start` (map frame) with covariance `start_cov`. The map's keyframes
  /// join the filter as known poses, thinned as the skeleton is; matches with them are loop
  /// closures. Throws std::invalid_argument for a graph the scans do not cover or with no
  /// matchable scan.
  /// With `seed` (a run resumed from its own snapshot) the filter is the seed's, robot included
  /// (`start` and `start_cov` are then not used), and the map's keyframes are this run's own:
  /// loop closures follow the usual rules.
  /// `node_covariances`: the map's own uncertainty where its saver knew it (nodeCovariances());
  /// the map's keyframes join the filter with it instead of as known poses.
  void continueMap(const PoseGraph& graph, const std::vector<LaserScan>& references, const Pose2& start,
                   const Mat3& start_cov, const std::optional<PsmSlamFilterSeed>& seed = std::nullopt,
                   const std::vector<std::pair<int64_t, Mat3>>& node_covariances = {});
  /// Localising in the continued map instead of extending it (call after continueMap): the map's
  /// reference scans stay where the map has them (the optimiser holds them fixed); this run's own
  /// reference scans are temporary. (All of the map's in the filter instead of its skeleton was
  /// tried: on MIT CSAIL the robot was then lost twice from a known start.)
  void freezeMap() { map_frozen_ = true; }
  /// Each graph node's marginal covariance in the map frame: the filter's now, or when it left
  /// the filter (nodes of a continued map: as loaded, where known).
  std::vector<std::pair<int64_t, Mat3>> nodeCovariances() const;
  /// What a snapshot keeps of the filter (see PsmSlamFilterSeed).
  PsmSlamFilterSeed filterSeed() const;
  /// The uncertainty of keyframe `id` relative to the robot, as a covariance in the map frame.
  Mat3 uncertaintyFromRobot(int64_t id) const;
  /// Cumulative odometry. Bad readings are counted and ignored.
  void addOdometry(const OdometryReading& reading);
  /// One laser scan; never throws for bad content (malformed scans count as unusable).
  PsmSlamScanResult addScan(const LaserScan& scan);
  /// Optimises the pose graph now and moves the filter and the trajectory with it.
  PoseGraphOptimizationSummary optimize();
  /// The final refinement (GraphRefinementParams): takes the background round's edges, optimises,
  /// matches the overlapping reference scans not yet tried pairwise from the graph's poses and
  /// adds the good matches as refinement edges; the caller's final optimize() weighs them.
  /// Returns the refinement's counts over the whole run.
  GraphRefinementSummary refine();

  /// One pose per scan, in input order, following the current pose graph.
  std::vector<PoseStamped> trajectory() const;
  const PoseGraph& graph() const { return graph_; }
  const PsmSlamStats& stats() const { return stats_; }
  const PsmSlamParams& params() const { return params_; }
  /// Whether anything has been received yet (the map frame is set by the first message, unless
  /// a saved map is continued).
  bool started() const { return clock_started_; }
  /// Keyframes that came from a continued map (ids below this).
  int64_t mapKeyframes() const { return map_keyframes_; }
  Pose2 currentPose() const { return filter_.robotPose(); }
  const PsmSlamFilter& filter() const { return filter_; }

 private:
  struct Keyframe {
    int64_t id = 0;
    int64_t utime = 0;
    Pose2 laser_mount;
    PreparedScan scan;
    LaserScan raw;  ///< as it came, for the unfiltered check of loop closures
  };
  /// A match of the current scan with one reference scan, as a robot-frame observation.
  struct Observation {
    int64_t keyframe = -1;
    Pose2 z;                  ///< robot pose in the keyframe's robot frame
    Mat3 R = Mat3::Zero();
    double overlap = 0.0;
    double error_index = 0.0;
    bool ambiguous = false;   ///< a distinct pose matched about as well (a look-alike place)
  };
  struct TrajectoryRecord {
    int64_t utime = 0;
    int64_t anchor = -1;      ///< keyframe id; -1 = `relative` is absolute
    Pose2 relative;
    Mat3 cov = Mat3::Zero();
  };
  /// An unconfirmed loop closure: where the filter had the robot, where the match put it.
  struct LoopHypothesis {
    size_t scan = 0;
    Pose2 robot, map_pose;
  };
  struct Candidate {
    int64_t id = 0;
    bool old = false;         ///< a loop-closure candidate
    double distance = 0.0;    ///< predicted, m, plus an angle term
    RelativePosePrediction prediction;
  };

  void start(const Pose2& pose);
  /// The first message's time starts the filter's clock.
  void startClock(int64_t utime);
  void addMapSkeleton(const Pose2& start);
  void restoreFilter(const PsmSlamFilterSeed& seed);
  void predictTo(int64_t utime);
  std::optional<Observation> matchKeyframe(const Keyframe& keyframe, const PreparedScan& scan, const Pose2& mount,
                                           const RelativePosePrediction& prior, bool loop_candidate, bool wide_search);
  /// Initial guesses for a loop-closure match: the prediction, and with `wide` a grid over its
  /// uncertainty when that is wider than PSM's basin.
  std::vector<Pose2> loopGuesses(const RelativePosePrediction& prior, bool wide) const;
  /// Matches the scan against the active reference from the odometry prior, and from the
  /// previous motion when the two disagree (stale odometry); the better match wins.
  std::optional<Observation> trackReference(const PreparedScan& scan, const Pose2& mount);
  /// Updates the filter with a good tracking match of `scan` (laser at `mount`); when it fails the
  /// χ² gate but the miss is a plausible odometry fault and the odometry's pose fits the scan
  /// markedly worse (odometry_fault_fit_ratio), the prior is inflated by the miss and the match applied.
  bool applyTrackingMatch(const Observation& o, const PreparedScan& scan, const Pose2& mount);
  bool plausibleOdometryFault(const RelativePosePrediction& prior, const Observation& o) const;
  void inflatePriorForMiss(const RelativePosePrediction& prior, const Observation& o);
  bool goodMatch(const Observation& o, bool loop_candidate) const;
  bool robotStill(const Observation& tracked) const;
  bool needsNewReference(const std::optional<Observation>& tracked);
  bool isOld(int64_t keyframe) const;
  /// Loop-closure match with an old reference: gated, and when the prior is too wide for the gate
  /// to tell look-alike places apart, checked against the closure's neighbouring reference scans
  /// and confirmed by a second closure. True if applied.
  bool applyLoopClosure(const Candidate& c, const Observation& o, const PreparedScan& scan, const LaserScan& raw);
  /// loop_check_unfiltered: the closure matched again with both scans' raw ranges lands elsewhere
  /// and fits there markedly better.
  bool refutedWithoutMedianFilter(const Candidate& c, const Observation& o, const LaserScan& raw);
  /// Two robot poses farther apart than loop_verify_translation / _rotation.
  bool beyondVerifyTolerance(const Pose2& a, const Pose2& b) const;
  enum class Verification { Agreed, Refuted, NoEvidence };
  /// The scan matched against the old reference scans that neighbour `closure` (taken in the same
  /// pass, near where the closure, robot pose `closure_z` in its frame, puts the robot), each
  /// from the pose the closure implies.
  Verification verifyWithNeighbours(int64_t closure, const Pose2& closure_z, const PreparedScan& scan,
                                    const Pose2& mount);
  bool confirmedByHypothesis(const Pose2& robot, const Pose2& map_pose, double prior_sigma) const;
  std::vector<Candidate> referenceCandidates() const;
  /// Matches candidates, then reuses one or adds the scan as a keyframe. True if a loop closed.
  /// Sets `map_matched` when an accepted match (the tracking one included) is with the map.
  bool selectReference(const LaserScan& scan, PreparedScan& prepared, const std::optional<Observation>& tracked,
                       bool& map_matched);
  void reuseReference(const Observation& chosen, const std::vector<Observation>& accepted);
  void addKeyframe(const LaserScan& scan, PreparedScan prepared, const std::vector<Observation>& accepted,
                   const std::optional<RelativePosePrediction>& link, int64_t previous);
  void addGraphEdge(int64_t from, int64_t to, const Pose2& z, const Mat3& R, PoseGraphEdgeKind kind);
  void marginaliseOldKeyframes();
  /// A skeleton keyframe lies within skeleton_spacing and skeleton_heading of `pose`.
  bool skeletonCovers(const Pose2& pose) const;
  void marginaliseKeyframe(int64_t id);
  void syncGraphFromFilter();
  /// The refinement's pairs for `current`: the nearest earlier reference scans within reach
  /// (GraphRefinementParams) but not in `excluded` (joined by an edge, or tried), and with
  /// `settled_only` none the filter still holds.
  std::vector<int64_t> refinementPartners(const Keyframe& current, const std::set<NodePair>& excluded,
                                          bool settled_only) const;
  /// Every pair not yet tried, from the graph's poses now; marks them tried. `settled_only`: only
  /// pairs of reference scans the filter no longer holds (it would not know why they moved).
  RefinementJob refinementJob(bool settled_only);
  void addRefinementEdges(const RefinementOutcome& outcome);
  /// After a loop-closure optimisation (GraphRefinementParams::online).
  void startBackgroundRefinement();
  /// Waits for the background round and adds its edges; true if any joined the graph.
  bool joinBackgroundRefinement();
  void record(int64_t utime, PsmSlamScanResult& result);
  const Keyframe& keyframe(int64_t id) const { return keyframes_[static_cast<size_t>(id)]; }

  PsmSlamParams params_;
  ScanMatcher matcher_;
  PsmSlamFilter filter_;
  PoseGraph graph_;
  std::vector<Keyframe> keyframes_;        ///< by id (ids are 0, 1, 2, ...)
  bool map_frozen_ = false;                ///< freezeMap()
  std::set<int64_t> filter_keyframes_;     ///< ids still in the filter
  std::vector<LoopHypothesis> hypotheses_;
  std::set<int64_t> skeleton_;             ///< older keyframes kept in the filter for loop closure
  std::map<int64_t, Mat3> left_filter_cov_;  ///< marginal covariance of keyframes no longer in the filter
  std::vector<TrajectoryRecord> records_;
  PsmSlamStats stats_;

  bool started_ = false;                   ///< the filter holds a robot pose
  bool clock_started_ = false;             ///< a message has set filter_utime_
  int64_t map_keyframes_ = 0;              ///< keyframes of a continued map: ids 0 .. this − 1
  OdometryIntegrator odometry_;
  bool have_odometry_ = false;
  Pose2 pending_motion_;                   ///< odometry since the last scan
  Mat3 pending_cov_ = Mat3::Zero();
  double pending_rotation_ = 0.0;          ///< |Δθ| summed since the last scan
  bool odometry_still_ = false;            ///< odometry did not move between the last two scans
  int64_t filter_utime_ = 0;               ///< time the filter's robot pose refers to
  std::optional<int64_t> last_scan_utime_;
  /// µs: scans further apart than this do not predict each other's motion (constant velocity).
  static constexpr int64_t kMaxConstantVelocityInterval = 1'000'000;
  bool moving_as_before_ = false;          ///< the last scan was at most that long before this one
  /// This scan comes after seconds without one (a stretch of lost scans, or the downtime of a run
  /// resumed from its snapshot): the robot has moved on from its reference scan.
  bool after_downtime_ = false;
  Pose2 last_scan_pose_;
  Pose2 last_scan_motion_;                 ///< robot motion between the last two scans
  int64_t keyframes_at_last_optimization_ = 0;
  bool loop_pending_ = false;              ///< closures not yet in an optimisation
  std::set<NodePair> refinement_tried_;    ///< pairs matched by the refinement, good or not
  GraphRefinementSummary refinement_;
  std::future<RefinementOutcome> background_refinement_;  ///< matched since the last loop closure
};

}  // namespace polarslam
