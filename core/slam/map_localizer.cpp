#include "slam/map_localizer.hpp"

#include "geometry/covariance.hpp"
#include "slam/psm_match.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace polarslam {
namespace {

Vec3 poseDifference(const Pose2& a, const Pose2& b) { return {a.x - b.x, a.y - b.y, wrapAngle(a.theta - b.theta)}; }

/// At most `count` of `items`, evenly spread over them.
template <typename T>
std::vector<T> evenlyThinned(const std::vector<T>& items, int count) {
  const size_t n = std::min(items.size(), static_cast<size_t>(std::max(1, count)));
  std::vector<T> kept;
  for (size_t k = 0; k < n; ++k) kept.push_back(items[k * items.size() / n]);
  return kept;
}

}  // namespace

MapLocalizer::MapLocalizer(const std::vector<MapReference>& references, PsmSlamParams params)
    : params_(std::move(params)), options_(params_.localization), matcher_(params_.psm), odometry_(params_.odometry) {
  std::vector<LaserScan> scans;  // every reference scan is map evidence, usable for PSM or not
  std::vector<Pose2> poses;
  for (const MapReference& r : references) {
    scans.push_back(r.scan);
    poses.push_back(r.pose);
    std::optional<PreparedScan> prepared = prepareMatchableScan(r.scan, params_.psm);
    if (prepared && finitePose(r.pose)) references_.push_back({r.id, r.pose, r.scan.laser_pose, std::move(*prepared)});
  }
  if (references_.empty()) throw std::invalid_argument("the map has no usable reference scan to localise against");
  const std::vector<Vec2> map_points = mapEndpoints(scans, poses, params_.psm.max_range);
  field_.emplace(map_points, params_.psm.max_range, options_.global_fit_distance);
  std::vector<Vec2> positions;
  for (const Reference& r : references_) positions.push_back(r.pose.translation());
  correlative_.emplace(map_points, positions,
                       CorrelativeSearchParams{options_.global_resolution, options_.global_sigma, options_.global_region_radius});
}

void MapLocalizer::setInitialPose(const Pose2& pose, const Mat3& cov) {
  pose_ = pose;
  cov_ = cov;
  localized_ = true;
  failures_in_a_row_ = 0;
}

void MapLocalizer::addOdometry(const OdometryReading& reading) {
  const OdometryMotionResult result = odometry_.add(reading);
  if (!result.ok()) return;
  have_odometry_ = true;
  const OdometryMotion& motion = *result.motion;
  const Mat3 Ja = composeJacobianA(pending_motion_, motion.delta), Jb = composeJacobianB(pending_motion_);
  pending_cov_ = Ja * pending_cov_ * Ja.transpose() + Jb * motion.cov * Jb.transpose();
  pending_motion_ = pending_motion_ * motion.delta;
}

// The same prediction as PSM SLAM's filter (psm_slam.cpp): odometry motion with the §17.6 model,
// plus a random walk per second of elapsed time.
void MapLocalizer::predictTo(int64_t utime) {
  const double dt = last_utime_ ? std::clamp(1e-6 * static_cast<double>(utime - *last_utime_), 0.0, 5.0) : 0.0;
  last_utime_ = std::max(last_utime_.value_or(utime), utime);
  Mat3 Q = pending_cov_;
  const double noise_xy = have_odometry_ ? params_.time_noise_xy : params_.no_odometry_noise_xy;
  const double noise_theta = have_odometry_ ? params_.time_noise_theta : params_.no_odometry_noise_theta;
  Q += Vec3(noise_xy * dt, noise_xy * dt, noise_theta * dt).asDiagonal();
  const Mat3 Ja = composeJacobianA(pose_, pending_motion_), Jb = composeJacobianB(pose_);
  cov_ = Ja * cov_ * Ja.transpose() + Jb * Q * Jb.transpose();
  pose_ = pose_ * pending_motion_;
  pending_motion_ = Pose2();
  pending_cov_.setZero();
}

std::optional<MapLocalizer::Fix> MapLocalizer::match(size_t index, const PreparedScan& scan, const Pose2& mount,
                                                     const Pose2& relative_guess, bool wide) {
  const Reference& ref = references_[index];
  const std::optional<RobotFrameMatch> m =
      matchInRobotFrame(matcher_, ref.scan, ref.laser_mount, scan, mount, relative_guess, params_, wide);
  if (!m) return std::nullopt;
  const Mat3 J = composeJacobianB(ref.pose);
  Fix fix;
  fix.reference = index;
  fix.pose = ref.pose * m->z;
  fix.cov = J * m->R * J.transpose();
  fix.error_index = m->error_index;
  fix.overlap = m->overlap;
  return fix;
}

bool MapLocalizer::goodFix(const Fix& fix, bool global) const {
  const double max_error = global ? params_.loop_max_error_index : params_.max_error_index;
  const double min_overlap = global ? options_.global_min_overlap : params_.min_overlap;
  return std::isfinite(fix.error_index) && fix.error_index <= max_error && fix.overlap >= min_overlap &&
         fix.cov.allFinite();
}

bool MapLocalizer::odometryFaultExplains(const Pose2& measured, double match_error_index, const PreparedScan& reference,
                                         const Pose2& reference_pose, const Pose2& reference_mount,
                                         const PreparedScan& scan, const Pose2& mount) {
  auto within = [&](const Pose2& from) {
    return isNear(from, measured, params_.max_odometry_fault_translation, params_.max_odometry_fault_rotation);
  };
  if (!within(pose_) && !within(constantVelocityPose())) return false;
  return predictionMisfits(matcher_, reference, reference_mount, scan, mount, between(reference_pose, pose_),
                           match_error_index, params_);
}

bool MapLocalizer::withinGate(const Vec3& innovation, const Mat3& innovation_cov) const {
  return innovation.dot(innovation_cov.ldlt().solve(innovation)) <= params_.chi2_gate;
}

bool MapLocalizer::applyFix(const Fix& fix, const PreparedScan& scan, const Pose2& mount) {
  const Vec3 nu = poseDifference(fix.pose, pose_);
  Mat3 S = cov_ + fix.cov;
  if (!withinGate(nu, S)) {
    const Reference& ref = references_[fix.reference];
    if (!odometryFaultExplains(fix.pose, fix.error_index, ref.scan, ref.pose, ref.laser_mount, scan, mount)) {
      ++stats_.gate_rejections;
      return false;
    }
    // A good match close to the prediction but outside the gate: the odometry step was wrong
    // (slip, a heading jump), as PSM SLAM treats it: widen the prior along the miss.
    cov_ += nu * nu.transpose();
    S = cov_ + fix.cov;
    ++stats_.odometry_faults;
  }
  const Mat3 K = cov_ * S.inverse();
  const Vec3 correction = K * nu;
  pose_ = Pose2(pose_.x + correction.x(), pose_.y + correction.y(), wrapAngle(pose_.theta + correction.z()));
  cov_ = (Mat3::Identity() - K) * cov_;
  cov_ = 0.5 * (cov_ + cov_.transpose());
  return true;
}

std::vector<size_t> MapLocalizer::nearestReferences(const Pose2& pose, size_t count) const {
  std::vector<std::pair<double, size_t>> near;
  const double reach2 = (options_.track_radius + 1e-6) * (options_.track_radius + 1e-6);
  for (size_t i = 0; i < references_.size(); ++i) {
    // Farther than track_radius whatever the frame (a rotation keeps lengths): no need for the
    // relative pose and its sine and cosine.
    if ((references_[i].pose.translation() - pose.translation()).squaredNorm() > reach2) continue;
    const Pose2 relative = between(references_[i].pose, pose);
    const double distance = relative.translation().norm();
    if (distance <= options_.track_radius && std::abs(relative.theta) <= options_.track_heading)
      near.emplace_back(distance + std::abs(relative.theta), i);
  }
  const size_t keep = std::min(near.size(), count);
  std::partial_sort(near.begin(), near.begin() + static_cast<long>(keep), near.end());
  std::vector<size_t> nearest;
  for (size_t k = 0; k < keep; ++k) nearest.push_back(near[k].second);
  return nearest;
}

MapLocalizer::Tracked MapLocalizer::track(const PreparedScan& scan, const Pose2& mount, MapLocalizationResult& result) {
  const std::vector<size_t> nearest = nearestReferences(pose_, static_cast<size_t>(options_.track_candidates));
  std::vector<Pose2> priors{pose_};
  const Pose2 disagreement = between(pose_, constantVelocityPose());
  if (have_odometry_ && (disagreement.translation().norm() >= params_.odometry_check_translation ||
                         std::abs(disagreement.theta) >= params_.odometry_check_rotation))
    priors.push_back(constantVelocityPose());
  std::optional<Fix> best;
  for (const size_t i : nearest)
    for (const Pose2& prior : priors) {
      std::optional<Fix> fix = match(i, scan, mount, between(references_[i].pose, prior), false);
      if (fix && goodFix(*fix, false) && (!best || fix->error_index < best->error_index)) best = fix;
    }
  if (best && applyFix(*best, scan, mount)) {
    result.matched = true;
    result.reference = references_[best->reference].id;
    unmatched_near_map_ = 0;
    newLocalReference(scan, mount);
    return Tracked::Matched;
  }
  unmatched_near_map_ = nearest.empty() ? 0 : unmatched_near_map_ + 1;
  if (!best) ++stats_.match_failures;
  return trackNewGround(scan, mount) ? Tracked::NewGround : Tracked::Failed;
}

void MapLocalizer::newLocalReference(const PreparedScan& scan, const Pose2& mount) {
  local_reference_ = LocalReference{pose_, cov_, mount, scan};
}

// The scan does not match the map: new ground, or the robot is not where it is thought to be.
// A match with the last scan that did (or with the last local reference) tells them apart: new
// ground is continuous with what the robot saw a moment ago; a kidnapped robot's view is not.
bool MapLocalizer::trackNewGround(const PreparedScan& scan, const Pose2& mount) {
  if (!local_reference_) return false;
  const LocalReference& ref = *local_reference_;
  const std::optional<RobotFrameMatch> m =
      matchInRobotFrame(matcher_, ref.scan, ref.laser_mount, scan, mount, between(ref.pose, pose_), params_, false);
  if (!m) return false;
  const Mat3 Ja = composeJacobianA(ref.pose, m->z), Jb = composeJacobianB(ref.pose);
  Fix fix;
  fix.pose = ref.pose * m->z;
  fix.cov = Jb * m->R * Jb.transpose();
  fix.error_index = m->error_index;
  fix.overlap = m->overlap;
  if (!goodFix(fix, false)) return false;
  if (!withinGate(poseDifference(fix.pose, pose_), cov_ + fix.cov) &&
      !odometryFaultExplains(fix.pose, fix.error_index, ref.scan, ref.pose, ref.laser_mount, scan, mount)) {
    ++stats_.gate_rejections;
    return false;
  }
  pose_ = fix.pose;
  cov_ = Ja * ref.cov * Ja.transpose() + fix.cov;
  ++stats_.new_ground_scans;
  if (!isNear(ref.pose, pose_, params_.keyframe_distance, params_.keyframe_angle) || m->overlap < params_.keyframe_min_overlap)
    newLocalReference(scan, mount);
  return true;
}

std::vector<Vec2> MapLocalizer::searchPoints(const LaserScan& raw) const {
  std::vector<size_t> readings;
  for (size_t i = 0; i < raw.size(); ++i)
    if (raw.valid(i) && raw.ranges[i] <= params_.psm.max_range) readings.push_back(i);
  std::vector<Vec2> points;
  for (const size_t i : evenlyThinned(readings, options_.global_points)) points.push_back(raw.laser_pose.transform(raw.point(i)));
  return points;
}

// PSM places the scan to a few millimetres where it overlaps a reference scan; where none was taken
// facing the same way (a robot turning where the map's run went straight) the search's own pose
// stands, good to its grid. Refinements that disagree are conflicting evidence: no fix.
std::optional<MapLocalizer::Fix> MapLocalizer::refineGlobalHit(const Pose2& hit, double score, const PreparedScan& scan,
                                                               const Pose2& mount) {
  std::vector<Fix> fixes;
  for (const size_t i : nearestReferences(hit, static_cast<size_t>(options_.track_candidates + 1))) {
    std::optional<Fix> fix = match(i, scan, mount, between(references_[i].pose, hit), false);
    if (fix && goodFix(*fix, true) && isNear(hit, fix->pose, options_.global_ambiguity_distance, params_.loop_ambiguity_heading))
      fixes.push_back(*fix);
  }
  if (fixes.empty()) {
    ++stats_.global_unrefined;
    Fix fix;
    fix.reference = nearestReference(hit);
    fix.pose = hit;
    const double sigma_xy = 2.0 * options_.global_resolution, sigma_theta = deg2rad(1.0);
    fix.cov = Vec3(sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_theta * sigma_theta).asDiagonal();
    fix.score = score;
    return fix;
  }
  Fix best = *std::min_element(fixes.begin(), fixes.end(),
                               [](const Fix& a, const Fix& b) { return a.error_index < b.error_index; });
  const bool agree = std::all_of(fixes.begin(), fixes.end(), [&](const Fix& f) {
    return isNear(best.pose, f.pose, options_.confirm_translation, options_.confirm_rotation);
  });
  if (!agree) {
    ++stats_.global_unsupported;
    return std::nullopt;
  }
  best.score = score;
  return best;
}

size_t MapLocalizer::nearestReference(const Pose2& pose) const {
  size_t nearest = 0;
  for (size_t i = 1; i < references_.size(); ++i)
    if ((references_[i].pose.translation() - pose.translation()).norm() <
        (references_[nearest].pose.translation() - pose.translation()).norm())
      nearest = i;
  return nearest;
}

void MapLocalizer::keepRecent(std::vector<SearchedScan>& scans, SearchedScan latest) const {
  scans.push_back(std::move(latest));
  const Pose2 now = scans.back().pose;
  std::erase_if(scans, [&](const SearchedScan& s) { return !isNear(s.pose, now, options_.global_sequence_distance, 2.0 * M_PI); });
  if (scans.size() > kMaxSequenceScans) scans.erase(scans.begin(), scans.end() - static_cast<long>(kMaxSequenceScans));
}

std::vector<Vec2> MapLocalizer::sequencePoints(const std::vector<SearchedScan>& scans, const Pose2& pose) const {
  std::vector<Vec2> all;
  for (const SearchedScan& searched : scans) {
    const Pose2 into_current = between(pose, searched.pose);
    for (const Vec2& p : searched.points) all.push_back(into_current.transform(p));
  }
  return evenlyThinned(all, options_.global_points);
}

double MapLocalizer::seeThroughLimit(const LaserScan& raw, const Pose2& current) const {
  return std::max(options_.global_max_see_through,
                  0.5 * field_->seeThrough(raw, current, options_.global_see_through_clearance));
}

CorrelativeQuery MapLocalizer::globalQuery() const {
  return {.min_score = options_.global_min_score,
          .rival_margin = options_.global_score_margin,
          .rival_distance = options_.global_ambiguity_distance,
          .rival_heading = params_.loop_ambiguity_heading,
          .best_at_least = 0.0,
          .go_on = {}};
}

std::optional<MapLocalizer::Fix> MapLocalizer::searchGlobally(const LaserScan& raw, const PreparedScan& scan,
                                                              const std::vector<Vec2>& points, const Pose2& current) {
  std::vector<CorrelativeHit> rivals;
  const double see_through_limit = seeThroughLimit(raw, current);
  CorrelativeQuery query = globalQuery();
  // Two rivals make the search ambiguous whatever else it would find: it ends there.
  query.go_on = [&](const std::vector<CorrelativeHit>& places) {
    admitRival(raw, places.back(), see_through_limit, rivals);
    return rivals.size() < 2;
  };
  stats_.global_nodes += correlative_->find(points, query).scored_nodes;
  ++stats_.global_searches;
  return fixAmong(raw, scan, rivals);
}

void MapLocalizer::admitRival(const LaserScan& raw, const CorrelativeHit& place, double see_through_limit,
                              std::vector<CorrelativeHit>& rivals) {
  // A place whose rays would pass through mapped walls is not where the robot is (a corridor seen
  // the wrong way round, a look-alike). Where the robot is thought to be now sees through walls
  // too, the map there is not one clean copy (a map bent by an unclosed loop holds a wall twice):
  // seeThroughLimit lets a place see through half as much as that. Of the others, one that
  // misfits (1 − score) more than global_misfit_ratio times the first does is no rival (PSM
  // SLAM's loop ambiguity rule compares error indices the same way).
  if (field_->seeThrough(raw, place.pose, options_.global_see_through_clearance) > see_through_limit)
    ++stats_.global_see_through;
  else if (rivals.empty() || 1.0 - place.score <= options_.global_misfit_ratio * (1.0 - rivals.front().score))
    rivals.push_back(place);
}

std::optional<MapLocalizer::Fix> MapLocalizer::fixAmong(const LaserScan& raw, const PreparedScan& scan,
                                                        const std::vector<CorrelativeHit>& places) {
  if (places.empty()) return std::nullopt;
  if (places.size() > 1) {
    ++stats_.global_ambiguous;
    return std::nullopt;
  }
  // Odometry bends a sequence of scans a little: the current scan alone places the robot.
  const CorrelativeHit here = correlative_->refine(searchPoints(raw), places.front().pose, kRefineTranslation, kRefineRotation);
  std::optional<Fix> fix = refineGlobalHit(here.pose, places.front().score, scan, raw.laser_pose);
  if (!fix) return std::nullopt;
  fix->fit = field_->fit(raw, fix->pose);
  if (fix->fit < options_.global_min_fit) return std::nullopt;
  return fix;
}

bool MapLocalizer::doubt(const LaserScan& scan, const Pose2& tracked) {
  if (nearestReferences(tracked, 1).empty() || field_->fit(scan, tracked) >= options_.doubt_max_fit) {
    doubted_.clear();
    last_doubt_at_.reset();
    return false;
  }
  const std::optional<PreparedScan> prepared = prepareMatchableScan(scan, params_.psm);
  if (!prepared) return false;
  keepRecent(doubted_, {tracked, searchPoints(scan)});
  if (last_doubt_at_ && isNear(*last_doubt_at_, tracked, options_.global_search_spacing, options_.global_search_turn))
    return false;
  last_doubt_at_ = tracked;
  ++stats_.doubt_searches;
  const auto start = std::chrono::steady_clock::now();
  const bool elsewhere = foundElsewhere(scan, *prepared, tracked);
  stats_.doubt_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (elsewhere) ++stats_.doubts;
  return elsewhere;
}

bool MapLocalizer::foundElsewhere(const LaserScan& scan, const PreparedScan& prepared, const Pose2& tracked) {
  const std::vector<Vec2> points = sequencePoints(doubted_, tracked);
  // The place must explain the scans markedly better than the tracked pose does, as a rival must;
  // the best pose within the refinement window around it stands for it (a tracked pose a few
  // centimetres off, or scans bent a little by odometry, are no evidence of being elsewhere).
  // Most doubts end with the search's first part, which prunes far more: no pose explains the
  // scans that much better, or the best one is where the robot is tracked (and sees through no
  // more walls than it); only otherwise does it go on to the rivals within the margin of the best.
  const double tracked_score = correlative_->refine(points, tracked, kRefineTranslation, kRefineRotation).score;
  // Where the tracked pose misfits so little that markedly less is below what the search's grid
  // can tell (the unrefined pose fit less than doubt_max_fit, a pose a few centimetres off fits
  // them), no place elsewhere can be shown to explain them better.
  if (1.0 - tracked_score < options_.global_misfit_ratio * correlative_->gridMisfit()) return false;
  const auto near_tracked = [&](const Pose2& pose) {
    return isNear(pose, tracked, options_.global_ambiguity_distance, params_.loop_ambiguity_heading);
  };
  const auto fits_fully = [&](const CorrelativeHit& place) { return field_->fit(scan, place.pose) >= options_.doubt_max_fit; };
  const auto markedly_better = [&](const CorrelativeHit& place) {
    return 1.0 - tracked_score > options_.global_misfit_ratio * (1.0 - place.score);
  };
  const double see_through_limit = seeThroughLimit(scan, tracked);
  CorrelativeQuery query = globalQuery();
  query.best_at_least = 1.0 - (1.0 - tracked_score) / options_.global_misfit_ratio;
  bool rivals_wanted = false;
  std::vector<CorrelativeHit> rivals;
  bool all_fit = true;  // once there are two rivals: every one of them fits the scan fully
  // The search ends as soon as the verdict below is "not elsewhere" whatever else it would find:
  // a rival where the robot is tracked; or two rivals or more, one of them not fitting fully or
  // the latest (the worst so far: places come best first) not markedly better than tracked.
  query.go_on = [&](const std::vector<CorrelativeHit>& places) {
    if (places.size() == 1) {
      rivals_wanted = !near_tracked(places.front().pose) ||
                      field_->seeThrough(scan, places.front().pose, options_.global_see_through_clearance) > see_through_limit;
      if (!rivals_wanted) return false;
    }
    const size_t before = rivals.size();
    admitRival(scan, places.back(), see_through_limit, rivals);
    if (rivals.size() == before) return true;
    const CorrelativeHit& latest = rivals.back();
    if (near_tracked(latest.pose)) return false;
    if (rivals.size() < 2) return true;
    if (rivals.size() == 2) all_fit = fits_fully(rivals.front());
    all_fit = all_fit && fits_fully(latest);
    return all_fit && markedly_better(latest);
  };
  stats_.global_nodes += correlative_->find(points, query).scored_nodes;
  if (!rivals_wanted) return false;  // no place, or the best is where the robot is tracked
  ++stats_.global_searches;
  if (rivals.empty() || std::any_of(rivals.begin(), rivals.end(), [&](const CorrelativeHit& r) { return near_tracked(r.pose); }))
    return false;
  // Look-alike places, none of them where the robot is tracked, each explaining the scans
  // markedly better and fitting the scan as a tracked pose beyond doubt does: wherever the robot
  // is, it is not there (a kidnapping in a symmetric building); which of them it is, is for the
  // searches while lost to settle. Places fitting less are no such evidence (on ground the map
  // does not hold, a repetitive building offers many that fit most of a scan).
  if (rivals.size() > 1) {
    ++stats_.global_ambiguous;
    return all_fit && markedly_better(rivals.back());
  }
  const std::optional<Fix> place = fixAmong(scan, prepared, rivals);
  if (!place || near_tracked(place->pose)) return false;
  return 1.0 - tracked_score > options_.global_misfit_ratio * (1.0 - place->score);
}

void MapLocalizer::lose() {
  localized_ = false;
  failures_in_a_row_ = unmatched_near_map_ = 0;
  hypothesis_.reset();
  last_search_at_.reset();
  searched_.clear();
  doubted_.clear();
  last_doubt_at_.reset();
  local_reference_.reset();  // seen from where the robot may no longer be
  ++stats_.losses;
}

void MapLocalizer::searchFrom(const Pose2& pose, int64_t utime) {
  lose();
  pose_ = last_scan_pose_ = pose;
  last_scan_motion_ = Pose2();
  cov_.setZero();
  pending_motion_ = Pose2();
  pending_cov_.setZero();
  last_utime_ = utime;
}

bool MapLocalizer::searchDue(const Pose2& predicted) const {
  return !last_search_at_ ||
         !isNear(*last_search_at_, predicted, options_.global_search_spacing, options_.global_search_turn);
}

double MapLocalizer::pathLength(const std::vector<SearchedScan>& scans) {
  double length = 0.0;
  for (size_t i = 1; i < scans.size(); ++i) length += (scans[i].pose.translation() - scans[i - 1].pose.translation()).norm();
  return length;
}

void MapLocalizer::searchAndConfirm(const LaserScan& raw, const PreparedScan& scan, const Pose2& predicted,
                                    MapLocalizationResult& result) {
  last_search_at_ = predicted;
  const std::optional<Fix> hit = searchGlobally(raw, scan, sequencePoints(searched_, predicted), predicted);
  if (!hit) {
    hypothesis_.reset();
    return;
  }
  const bool seen_along_enough =
      options_.confirm_sequence_length > 0.0 && pathLength(searched_) >= options_.confirm_sequence_length;
  const bool confirmed =
      seen_along_enough || (hypothesis_ && isNear(hypothesis_->pose * between(hypothesis_->odometry_pose, predicted),
                                                  hit->pose, options_.confirm_translation, options_.confirm_rotation));
  if (!confirmed) {
    if (hypothesis_) ++stats_.global_unconfirmed;
    hypothesis_ = Hypothesis{hit->pose, predicted};
    return;
  }
  pose_ = hit->pose;
  cov_ = hit->cov;
  localized_ = true;
  failures_in_a_row_ = 0;
  hypothesis_.reset();
  result.found = result.matched = true;
  result.reference = references_[hit->reference].id;
  ++stats_.fixes;
  if (stats_.first_fix_scan < 0) stats_.first_fix_scan = static_cast<int64_t>(stats_.scans - 1);
}

MapLocalizationResult MapLocalizer::addScan(const LaserScan& scan) {
  ++stats_.scans;
  MapLocalizationResult result;
  predictTo(scan.utime);
  const Pose2 predicted = pose_;
  std::optional<PreparedScan> prepared = prepareMatchableScan(scan, params_.psm);
  if (!prepared) {
    ++stats_.unusable_scans;
  } else if (localized_) {
    result.usable = true;
    const Tracked tracked = track(*prepared, scan.laser_pose, result);
    failures_in_a_row_ = tracked == Tracked::Failed ? failures_in_a_row_ + 1 : 0;
    if (doubt(scan, pose_)) {
      const size_t doubted = doubted_.size() - 1;  // the doubted scans before this one: re-placed with the rest
      lose();
      lost_since_ = online_.size() >= doubted ? online_.size() - doubted : 0;
    } else if (failures_in_a_row_ >= options_.lost_after_scans || unmatched_near_map_ >= options_.lost_near_map_after_scans) {
      // The scans of the failed run (placed by odometry or the local reference): re-placed with the rest.
      const size_t failed = static_cast<size_t>(std::max(failures_in_a_row_, unmatched_near_map_)) - 1;
      lose();
      lost_since_ = online_.size() >= failed ? online_.size() - failed : 0;
    } else if (tracked == Tracked::NewGround && largestPositionSigma(cov_) > options_.max_off_map_sigma) {
      ++stats_.off_map_timeouts;
      lose();  // the poses so far still hold what odometry knew; from here on they are re-placed
    }
  } else {
    result.usable = true;
    keepRecent(searched_, {predicted, searchPoints(scan)});
    if (searchDue(predicted)) {
      const auto start = std::chrono::steady_clock::now();
      searchAndConfirm(scan, *prepared, predicted, result);
      stats_.search_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    if (localized_) searched_.clear();
  }
  dead_reckoning_.push_back(predicted);
  last_scan_motion_ = result.found ? Pose2() : between(last_scan_pose_, pose_);  // a fix is not a motion
  last_scan_pose_ = pose_;
  result.localized = localized_;
  result.pose = {scan.utime, pose_, cov_};
  record(result);
  return result;
}

void MapLocalizer::record(const MapLocalizationResult& result) {
  const size_t index = online_.size();
  if (result.matched) ++stats_.matched_scans;
  if (!localized_) ++stats_.odometry_only_scans;
  if (!localized_ && !lost_since_) lost_since_ = index;
  if (result.found && lost_since_) {
    stretches_.push_back({*lost_since_, index});
    lost_since_.reset();
  }
  online_.push_back(result.pose);
  localized_flags_.push_back(localized_);
}

std::vector<PoseStamped> MapLocalizer::trajectory() const {
  std::vector<PoseStamped> poses = online_;
  for (const Stretch& s : stretches_) {
    // Scans [first, last) had dead-reckoning poses; the fix at `last` places that chain.
    const Pose2 anchor = online_[s.last].pose * dead_reckoning_[s.last].inverse();
    for (size_t i = s.first; i < s.last; ++i) poses[i].pose = anchor * dead_reckoning_[i];
  }
  return poses;
}

}  // namespace polarslam
