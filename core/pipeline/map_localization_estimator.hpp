#pragma once
// `polarslam run --pipeline psm-slam --load-map M --mode localize`: localisation in a stored map,
// the map unchanged (docs/maps.md).
//
// Until the robot is placed in the map (the --initial-pose, or a fix of the global search,
// core/slam/map_localizer.hpp) its poses are odometry only. Once placed, PSM SLAM tracks it over
// the map held fixed (PsmSlamEstimator::localizeIn): matches with the map's reference scans tie
// it to the map, and on ground the map does not hold it maps on with temporary reference scans
// of its own, closing loops with them and with the map, so a robot that leaves the map comes
// back to it consistent (Cartographer's pure localisation does the same). `lost_near_map_after_scans`
// scans in a row near the map's reference scans (within track_radius and track_heading) without a
// match with any of them (PsmSlamScanResult::map_matched) lose it: the temporary reference scans
// are dropped and the global search takes over again.
//
// Online trajectory: the poses at scan time. Final trajectory: each tracked stretch as its PSM
// SLAM graph places it after a final optimisation, each searched stretch re-placed from the fix
// that ended it, and a lost stretch's drifted scans since its last map match with them where
// that fix explains the loss as drift (Tail). The map's grid is drawn again with the localised
// trajectory.
//
// With localization.temporary_mapping off, MapLocalizer tracks too: the map's reference scans
// only, and a single local reference on new ground.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "map/map_store.hpp"
#include "pipeline/estimator.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "slam/map_localizer.hpp"

namespace polarslam {

/// Moves the last of `poses` to `corrected_last` and the others part of the way: pose i is rotated
/// about `pivot` and translated by the share (weights[0] + … + weights[i]) / Σ weights of that
/// correction (all of it when the weights sum to 0), as a chain of relative poses from `pivot`
/// closed at its end takes a correction in proportion to the uncertainty each link adds.
void spreadCorrection(std::span<PoseStamped> poses, const Vec2& pivot, const Pose2& corrected_last,
                      const std::vector<double>& weights);

/// The "localization" report figures of a localiser (`seconds` spent in it).
nlohmann::json localizationReportJson(const MapLocalizer& localizer, double seconds);

class MapLocalizationEstimator : public Estimator {
 public:
  /// `initial_pose`: a known start in the map frame; without it the start is searched globally.
  MapLocalizationEstimator(StoredMap map, PsmSlamEstimatorConfig config, std::optional<Pose2> initial_pose,
                           const Mat3& initial_cov = Mat3::Zero());

  std::string name() const override { return "psm-localize"; }
  void onOdometry(const OdometryReading& odometry) override;
  void onLaser(const LaserScan& scan) override;
  const std::vector<PoseStamped>& trajectory() const override { return finished_ ? final_ : online_; }
  const std::vector<PoseStamped>& onlineTrajectory() const override { return online_; }
  /// Adds the "localization" figures (and "psm_slam" of the last tracked stretch) and writes
  /// map.png with the trajectory into `out_dir`.
  void finish(const std::string& out_dir, nlohmann::json& report) override;

  const MapLocalizer& localizer() const { return localizer_; }
  const StoredMap& map() const { return map_; }
  /// Whether the robot is placed in the map now.
  bool localized() const { return tracker_ ? true : localizer_.localized(); }
  /// Per scan: whether its online pose was tied to the map (placed in it).
  const std::vector<bool>& localizedFlags() const { return localized_flags_; }
  /// What the latest scan gave.
  const MapLocalizationResult& lastResult() const { return last_result_; }
  double seconds() const { return seconds_; }

 private:
  void startTracking(const Pose2& pose, const Mat3& cov);
  void track(const LaserScan& scan);
  void search(const LaserScan& scan);
  /// Unmatched near the map for too long: back to the global search.
  void loseTracking(int64_t utime);
  /// A reference scan of the map lies within track_radius and track_heading of `pose`.
  bool nearMap(const Pose2& pose) const;
  /// Adds the reference scans the current tracked stretch added to the map's.
  void countTemporaryReferenceScans();
  /// A fix ended the search that followed a loss: re-places the lost stretch's tail (see Tail).
  void replaceTail(const std::vector<PoseStamped>& searched);

  /// The scans of a lost stretch since its last match with the map, in placed_ [begin, end): the
  /// robot was placed by its own temporary reference scans there, drifting. Where the fix that
  /// ends the search puts the loss within the drift that distance allows (a doubt or a timeout
  /// caught the drift, no kidnapping), the correction is spread along the tail, as a pose graph's
  /// odometry chain would: nothing at the last map match, all of it at the loss.
  struct Tail {
    size_t begin = 0, end = 0;  ///< placed_[begin − 1] is the last map match
  };

  StoredMap map_;
  PsmSlamEstimatorConfig config_;
  MapLocalizer localizer_;
  std::unique_ptr<PsmSlamEstimator> tracker_;  ///< placed in the map (temporary mapping)
  std::optional<OdometryReading> last_odometry_;
  int unmatched_near_map_ = 0;             ///< usable scans in a row near the map without a map match
  size_t map_matched_scans_ = 0;           ///< tracked scans matched with the map
  size_t tracking_losses_ = 0, tracked_stretches_ = 0, temporary_reference_scans_ = 0, replaced_tails_ = 0;
  size_t search_start_ = 0;                ///< the localiser's first scan of the current search
  size_t stretch_scans_ = 0;               ///< scans of the current tracked stretch
  size_t last_map_match_ = 0;              ///< ... the last matched with the map (0: its start)
  std::optional<Tail> tail_;               ///< of the stretch lost last, until the next fix
  std::vector<PoseStamped> placed_;        ///< final poses of the stretches that have ended
  std::vector<PoseStamped> online_, final_;
  std::vector<bool> localized_flags_;
  bool finished_ = false;
  double seconds_ = 0.0;
  MapLocalizationResult last_result_;
};

}  // namespace polarslam
