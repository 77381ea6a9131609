#include "pipeline/map_localization_estimator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "grid/grid_files.hpp"
#include "grid/graph_scan_store.hpp"
#include "io/stopwatch.hpp"

namespace polarslam {

MapLocalizationEstimator::MapLocalizationEstimator(StoredMap map, PsmSlamEstimatorConfig config,
                                                   std::optional<Pose2> initial_pose, const Mat3& initial_cov)
    : map_(std::move(map)), config_(std::move(config)), localizer_(mapReferences(map_), config_.slam) {
  if (!initial_pose) return;
  if (config_.slam.localization.temporary_mapping) startTracking(*initial_pose, initial_cov);
  else localizer_.setInitialPose(*initial_pose, initial_cov);
}

void MapLocalizationEstimator::onOdometry(const OdometryReading& odometry) {
  const auto start = std::chrono::steady_clock::now();
  last_odometry_ = odometry;
  localizer_.addOdometry(odometry);  // the search takes over from the latest reading when tracking is lost
  if (tracker_) tracker_->onOdometry(odometry);
  seconds_ += secondsSince(start);
}

void MapLocalizationEstimator::onLaser(const LaserScan& scan) {
  const auto start = std::chrono::steady_clock::now();
  if (tracker_) track(scan);
  else search(scan);
  online_.push_back(last_result_.pose);
  localized_flags_.push_back(last_result_.localized);
  seconds_ += secondsSince(start);
}

void MapLocalizationEstimator::startTracking(const Pose2& pose, const Mat3& cov) {
  tracker_ = std::make_unique<PsmSlamEstimator>(config_);
  tracker_->localizeIn(map_, pose, cov);
  if (last_odometry_) tracker_->onOdometry(*last_odometry_);  // its integrator starts from the latest reading
  unmatched_near_map_ = 0;
  stretch_scans_ = last_map_match_ = 0;
  ++tracked_stretches_;
}

void MapLocalizationEstimator::search(const LaserScan& scan) {
  last_result_ = localizer_.addScan(scan);
  if (!config_.slam.localization.temporary_mapping || !last_result_.found) return;
  // The search stretch re-placed from the fix, as dead reckoning.
  const std::vector<PoseStamped> searched = localizer_.trajectory();
  replaceTail(searched);
  placed_.insert(placed_.end(), searched.begin() + static_cast<long>(search_start_), searched.end());
  startTracking(last_result_.pose.pose, last_result_.pose.cov);
}

void MapLocalizationEstimator::track(const LaserScan& scan) {
  tracker_->onLaser(scan);
  const PsmSlamScanResult& r = tracker_->lastResult();
  last_result_ = MapLocalizationResult{};
  last_result_.pose = tracker_->onlineTrajectory().back();
  last_result_.usable = r.usable;
  last_result_.localized = true;
  last_result_.matched = r.map_matched;
  map_matched_scans_ += r.map_matched ? 1 : 0;
  if (r.map_matched) last_map_match_ = stretch_scans_;
  ++stretch_scans_;
  // On new ground the temporary reference scans carry the robot; where the map's reference scans
  // should be seen and are not, it is not where it is thought to be (a kidnapping, a look-alike).
  if (r.map_matched) unmatched_near_map_ = 0;
  else if (r.usable && nearMap(last_result_.pose.pose)) ++unmatched_near_map_;
  if (unmatched_near_map_ >= config_.slam.localization.lost_near_map_after_scans ||
      (r.usable && localizer_.doubt(scan, last_result_.pose.pose)))
    loseTracking(scan.utime);
}

bool MapLocalizationEstimator::nearMap(const Pose2& pose) const {
  const MapLocalizationParams& p = config_.slam.localization;
  return std::any_of(map_.graph.nodes().begin(), map_.graph.nodes().end(),
                     [&](const PoseGraphNode& node) { return isNear(node.pose, pose, p.track_radius, p.track_heading); });
}

void MapLocalizationEstimator::countTemporaryReferenceScans() {
  const PsmSlam& slam = tracker_->slam();
  temporary_reference_scans_ += slam.graph().nodes().size() - static_cast<size_t>(slam.mapKeyframes());
}

void MapLocalizationEstimator::loseTracking(int64_t utime) {
  const std::vector<PoseStamped> tracked = tracker_->slam().trajectory();
  // The scans since the last map match keep their tracked poses until the next fix: it re-places
  // them if it explains the loss as drift (replaceTail); before a kidnapping they are right.
  const size_t begin = placed_.size();
  placed_.insert(placed_.end(), tracked.begin(), tracked.end());
  tail_.reset();
  if (tracked.size() == stretch_scans_ && last_map_match_ + 1 < tracked.size())
    tail_ = Tail{begin + last_map_match_ + 1, placed_.size()};
  countTemporaryReferenceScans();
  localizer_.searchFrom(tracked.back().pose, utime);
  search_start_ = localizer_.onlineTrajectory().size();
  tracker_.reset();
  last_result_.localized = false;
  ++tracking_losses_;
}

namespace {

/// m travelled along `poses`.
double pathLength(std::span<const PoseStamped> poses) {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i)
    length += (poses[i].pose.translation() - poses[i - 1].pose.translation()).norm();
  return length;
}

/// `p` turned by `angle` about `pivot`.
Vec2 turnedAbout(const Vec2& pivot, const Vec2& p, double angle) {
  return Pose2(pivot.x(), pivot.y(), angle).transform(p - pivot);
}

}  // namespace

void MapLocalizationEstimator::replaceTail(const std::vector<PoseStamped>& searched) {
  if (!tail_ || search_start_ >= searched.size()) return;
  const Tail tail = *tail_;
  tail_.reset();
  // The tail runs from the last map match, placed_[begin − 1], to the loss, placed_[end − 1].
  const std::span<PoseStamped> from_match = std::span(placed_).subspan(tail.begin - 1, tail.end - tail.begin + 1);
  const std::vector<PoseStamped>& online = localizer_.onlineTrajectory();
  // The search's dead reckoning started at the loss; the fix re-placed it rigidly.
  const Pose2 correction = searched[search_start_].pose * online[search_start_].pose.inverse();
  const Pose2 lost = from_match.back().pose, found = correction * lost;
  const double travelled = pathLength(from_match) + pathLength(std::span(searched).subspan(search_start_));
  const double shift = (found.translation() - lost.translation()).norm();
  const double turn = std::abs(wrapAngle(found.theta - lost.theta));
  const MapLocalizationParams& limits = config_.slam.localization;
  if (shift > limits.tail_max_shift + limits.tail_shift_per_metre * travelled ||
      turn > limits.tail_max_turn + limits.tail_turn_per_metre * travelled)
    return;
  ++replaced_tails_;
  // Spread by the growth of the position variance along the tail (by distance where it did not grow).
  std::vector<double> growth, distance;
  for (size_t i = 1; i < from_match.size(); ++i) {
    const auto trace = [&](size_t k) { return from_match[k].cov.topLeftCorner<2, 2>().trace(); };
    growth.push_back(std::max(0.0, trace(i) - trace(i - 1)));
    distance.push_back((from_match[i].pose.translation() - from_match[i - 1].pose.translation()).norm());
  }
  const bool grew = std::accumulate(growth.begin(), growth.end(), 0.0) > 0.0;
  spreadCorrection(from_match.subspan(1), from_match.front().pose.translation(), found, grew ? growth : distance);
}

void spreadCorrection(std::span<PoseStamped> poses, const Vec2& pivot, const Pose2& corrected_last,
                      const std::vector<double>& weights) {
  if (poses.empty()) return;
  const Pose2 last = poses.back().pose;
  const double dtheta = wrapAngle(corrected_last.theta - last.theta);
  const Vec2 dt = corrected_last.translation() - turnedAbout(pivot, last.translation(), dtheta);
  const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
  double along = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) {
    along += i < weights.size() ? weights[i] : 0.0;
    const double share = total > 0.0 ? along / total : 1.0;
    Pose2& pose = poses[i].pose;
    const Vec2 p = turnedAbout(pivot, pose.translation(), share * dtheta) + share * dt;
    pose = {p.x(), p.y(), wrapAngle(pose.theta + share * dtheta)};
  }
  poses.back().pose = corrected_last;  // exactly, whatever rounding
}

nlohmann::json localizationReportJson(const MapLocalizer& localizer, double seconds) {
  const MapLocalizerStats& s = localizer.stats();
  return {{"reference_scans", localizer.referenceCount()},
          {"scans", s.scans},
          {"unusable_scans", s.unusable_scans},
          {"matched_scans", s.matched_scans},
          {"odometry_only_scans", s.odometry_only_scans},
          {"match_failures", s.match_failures},
          {"new_ground_scans", s.new_ground_scans},
          {"off_map_timeouts", s.off_map_timeouts},
          {"gate_rejections", s.gate_rejections},
          {"odometry_faults", s.odometry_faults},
          {"global_searches", s.global_searches},
          {"global_nodes", s.global_nodes}, {"global_unrefined", s.global_unrefined},
          {"global_ambiguous", s.global_ambiguous},
          {"global_see_through", s.global_see_through},
          {"global_unsupported", s.global_unsupported},
          {"global_unconfirmed", s.global_unconfirmed},
          {"doubt_searches", s.doubt_searches},
          {"doubts", s.doubts},
          {"doubt_seconds", s.doubt_seconds},
          {"search_seconds", s.search_seconds},
          {"fixes", s.fixes},
          {"losses", s.losses},
          {"first_fix_scan", s.first_fix_scan},
          {"localized_at_end", localizer.localized()},
          {"seconds", seconds}};
}

void MapLocalizationEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  const bool tracking = tracker_ != nullptr;
  if (tracker_) {
    nlohmann::json tracked;
    tracker_->finish("", tracked);  // the final optimisation of the tracked stretch
    report["psm_slam"] = tracked["psm_slam"];
    const std::vector<PoseStamped>& poses = tracker_->trajectory();
    placed_.insert(placed_.end(), poses.begin(), poses.end());
    countTemporaryReferenceScans();
  } else {
    // Never found again: the search stays dead reckoning.
    const std::vector<PoseStamped> searched = localizer_.trajectory();
    placed_.insert(placed_.end(), searched.begin() + static_cast<long>(search_start_), searched.end());
  }
  final_ = std::move(placed_);
  finished_ = true;
  nlohmann::json section = localizationReportJson(localizer_, seconds_);
  section["localized_at_end"] = localized();
  section["temporary_mapping"] = config_.slam.localization.temporary_mapping;
  if (config_.slam.localization.temporary_mapping) {
    section["scans"] = online_.size();
    section["searched_scans"] = localizer_.stats().scans;
    section["matched_scans"] = localizer_.stats().matched_scans + map_matched_scans_;  // the fixes, and while tracking
    section["tracked_stretches"] = tracked_stretches_;
    section["tracking_losses"] = tracking_losses_;
    section["replaced_tails"] = replaced_tails_;
    section["temporary_reference_scans"] = temporary_reference_scans_;
    section["tracking_at_end"] = tracking;
  }
  report["localization"] = section;
  if (out_dir.empty() || map_.scans.empty()) return;
  GraphScanStore store;
  for (const MapReferenceScan& s : map_.scans) store.add(s.scan, s.anchor);
  const GraphGrid grid = buildGraphGrid(store, map_.graph, gridOptions(config_.map));
  GridPicture picture = graphGridPicture(grid, map_.graph, final_);
  picture.title = "psm-localize: the stored map and the localised trajectory";
  const GridFiles files = writeGridFiles(out_dir, grid.grid, grid.slice, picture);
  report["grid"] = {{"written", true}, {"scans", store.size()}, {"files", {files.ot, files.bt, files.pgm, files.yaml, files.png}}};
}

}  // namespace polarslam
