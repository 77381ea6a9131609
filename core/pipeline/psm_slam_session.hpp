#pragma once
// PSM SLAM with its map options, as `polarslam run --pipeline psm-slam` and the live
// polarslam-psm-slam both run it: mapping from scratch, localisation in a saved map (--load-map M
// --mode localize) or mapping on from one (--mode continue), with --initial-pose and --save-map.
// The offline run feeds the estimator from a log; the live process feeds the same estimator from
// LCM and publishes what each scan gave (PsmSlamSession::onLaser), so both give the same poses.
#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>

#include "pipeline/estimator.hpp"
#include "pipeline/map_continuation_estimator.hpp"
#include "pipeline/map_localization_estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {

struct SavedMapOptions {
  std::string load_map;               ///< a saved map to work in; empty: map from scratch
  std::string mode = "localize";      ///< with load_map: localize | continue
  std::optional<Pose2> initial_pose;  ///< with load_map: the start in the map frame; none: searched
  Mat3 initial_cov = Mat3::Zero();    ///< ... and its covariance
  std::optional<PsmSlamFilterSeed> filter_seed;  ///< continue: resuming a run from its own snapshot
  std::string save_map;               ///< folder the map is saved to (not when localising)
  /// load_map as already read (a snapshot about to be resumed): it is not read a second time.
  std::shared_ptr<const StoredMap> loaded_map;
};

/// "x,y,theta" (m, m, rad); throws std::runtime_error naming --initial-pose otherwise.
Pose2 parseInitialPose(const std::string& text);

/// The estimator for `options`. Throws std::runtime_error for options that do not go together
/// and MapFormatError for a bad saved map.
std::unique_ptr<Estimator> makePsmSlamEstimator(PsmSlamEstimatorConfig config, const SavedMapOptions& options);

/// What one scan gave, for publishing.
struct PsmSlamScanOutput {
  PoseStamped pose;                    ///< robot pose in the map frame now
  std::optional<AnchoredPose> anchor;  ///< the same relative to a graph node (none when localising)
  bool usable = false;                 ///< the scan could be matched at all
  bool graph_changed = false;          ///< new reference scan, loop closure or optimisation
  bool optimized = false;
};

class PsmSlamSession {
 public:
  PsmSlamSession(PsmSlamEstimatorConfig config, const SavedMapOptions& options);

  void onOdometry(const OdometryReading& reading);
  PsmSlamScanOutput onLaser(const LaserScan& scan);
  /// Whether any message has come in.
  bool started() const { return started_; }
  /// The SLAM whose graph is published: none while localising or searching a continued map's start.
  const PsmSlam* slam() const;
  bool savesMap() const { return !save_map_.empty(); }
  const std::string& saveMapFolder() const { return save_map_; }
  /// Saves the map as it is now, with its grid (a SAVE_MAP request). Throws MapFormatError.
  void saveMapNow() const;
  /// At the end: the final optimisation and, with --save-map, the map saved. The report figures.
  nlohmann::json finish();
  /// After finish(): one pose per scan, in the map frame (what trajectory.tum holds offline).
  const std::vector<PoseStamped>& finalTrajectory() const { return estimator_->trajectory(); }

  /// Crash recovery: whether there is state to snapshot (mapping, or localising; not while a
  /// continued map's start is still searched).
  bool canSnapshot() const { return mapping() != nullptr || localization_ != nullptr; }
  /// Writes the map so far (localising: the map worked in) and where the robot is (resume.json
  /// with `resume`'s fields added) to `dir`, atomically, as a saved map without its grid. Throws
  /// MapFormatError.
  void writeSnapshot(const std::string& dir, nlohmann::json resume) const;

 private:
  const PsmSlamEstimator* mapping() const;

  std::unique_ptr<Estimator> estimator_;
  PsmSlamEstimator* scratch_ = nullptr;               ///< mapping from scratch
  MapContinuationEstimator* continuation_ = nullptr;  ///< --mode continue
  MapLocalizationEstimator* localization_ = nullptr;  ///< --mode localize
  std::string save_map_;
  bool started_ = false;
  std::optional<OdometryReading> last_odometry_;
};

/// A crash-recovery snapshot read back: the session options that resume from it (--mode continue
/// in its map, from where the robot was), the odometry reading to prime the session with, and
/// the fields the process added.
struct SessionSnapshot {
  SavedMapOptions options;
  std::optional<OdometryReading> last_odometry;
  nlohmann::json resume;
};
/// Reads the snapshot in `dir` (nullopt when there is none) for a session that was started with
/// `options` (its --save-map stays). Throws MapFormatError for a damaged one.
std::optional<SessionSnapshot> readSessionSnapshot(const std::string& dir, const SavedMapOptions& options);
/// The same for the map already loaded from `dir` (which must hold a resume.json).
SessionSnapshot sessionSnapshotOf(const StoredMap& map, const std::string& dir, const SavedMapOptions& options);

}  // namespace polarslam
