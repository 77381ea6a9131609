#include "slam/psm_slam.hpp"

#include "geometry/covariance.hpp"
#include "slam/psm_match.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace polarslam {
namespace {

/// Jacobian of the inverse pose ⊖p with respect to p.
Mat3 inverseJacobian(const Pose2& p) {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  const Pose2 inv = p.inverse();
  Mat3 J;
  J << -c, -s, inv.y, s, -c, -inv.x, 0.0, 0.0, -1.0;
  return J;
}

/// The pose of b's keyframe seen from a's keyframe, from the same scan matched against both:
/// z_a ⊕ ⊖z_b, with the two (independent) match covariances propagated.
std::pair<Pose2, Mat3> composeThroughScan(const Pose2& z_a, const Mat3& R_a, const Pose2& z_b, const Mat3& R_b) {
  const Pose2 z_b_inv = z_b.inverse();
  const Mat3 Ja = composeJacobianA(z_a, z_b_inv);
  const Mat3 Jb = composeJacobianB(z_a) * inverseJacobian(z_b);
  return {z_a * z_b_inv, Ja * R_a * Ja.transpose() + Jb * R_b * Jb.transpose()};
}

}  // namespace

PsmSlam::PsmSlam(PsmSlamParams params) : params_(std::move(params)), matcher_(params_.psm), odometry_(params_.odometry) {
  filter_.reset(Pose2(), Mat3::Zero());
}

void PsmSlam::start(const Pose2& pose) {
  filter_.reset(pose, Mat3::Zero());
  last_scan_pose_ = pose;
  started_ = true;
}

void PsmSlam::startClock(int64_t utime) {
  if (!started_) start(Pose2());
  if (clock_started_) return;
  filter_utime_ = utime;
  clock_started_ = true;
}

void PsmSlam::continueMap(const PoseGraph& graph, const std::vector<LaserScan>& references, const Pose2& start_pose,
                          const Mat3& start_cov, const std::optional<PsmSlamFilterSeed>& seed,
                          const std::vector<std::pair<int64_t, Mat3>>& node_covariances) {
  if (clock_started_ || !keyframes_.empty()) throw std::logic_error("continueMap: call it before the first message");
  if (references.size() != graph.nodes().size())
    throw std::invalid_argument("the map has " + std::to_string(graph.nodes().size()) + " graph nodes but " +
                                std::to_string(references.size()) + " reference scans");
  for (size_t i = 0; i < references.size(); ++i) {
    const int64_t id = static_cast<int64_t>(i);
    if (graph.nodes()[i].id != id)
      throw std::invalid_argument("the map's graph nodes are not numbered 0.." + std::to_string(references.size() - 1));
    std::optional<PreparedScan> prepared = prepareMatchableScan(references[i], params_.psm);
    keyframes_.push_back(
        {id, references[i].utime, references[i].laser_pose, prepared ? std::move(*prepared) : PreparedScan{}, references[i]});
  }
  graph_ = graph;
  for (const auto& [id, cov] : node_covariances) left_filter_cov_[id] = cov;
  keyframes_at_last_optimization_ = static_cast<int64_t>(keyframes_.size());
  filter_.reset(start_pose, start_cov);
  last_scan_pose_ = start_pose;
  started_ = true;
  if (seed) {
    restoreFilter(*seed);  // its own map: map_keyframes_ stays 0
  } else {
    map_keyframes_ = static_cast<int64_t>(keyframes_.size());
    addMapSkeleton(start_pose);
  }
}

void PsmSlam::restoreFilter(const PsmSlamFilterSeed& seed) {
  for (const int64_t id : seed.filter.ids) {
    if (id < 0 || id >= static_cast<int64_t>(keyframes_.size()) || keyframe(id).scan.empty())
      throw std::invalid_argument("the snapshot's filter keyframe " + std::to_string(id) + " is not a matchable map node");
  }
  filter_.restore(seed.filter);
  filter_keyframes_.insert(seed.filter.ids.begin(), seed.filter.ids.end());
  for (const int64_t id : seed.skeleton) {
    if (!filter_keyframes_.count(id))
      throw std::invalid_argument("the snapshot's skeleton keyframe " + std::to_string(id) + " is not in its filter");
    skeleton_.insert(id);
  }
  last_scan_pose_ = filter_.robotPose();
  after_downtime_ = true;
}

std::vector<std::pair<int64_t, Mat3>> PsmSlam::nodeCovariances() const {
  // The first node defines the frame (zero covariance): a floor keeps every one positive definite.
  const Mat3 floor = covarianceFloor(1e-4, 1e-5);
  std::vector<std::pair<int64_t, Mat3>> out;
  for (const PoseGraphNode& node : graph_.nodes()) {
    std::optional<Mat3> cov;
    if (filter_.hasKeyframe(node.id)) cov = filter_.keyframeCovariance(node.id);
    else if (const auto it = left_filter_cov_.find(node.id); it != left_filter_cov_.end()) cov = it->second;
    if (cov) out.emplace_back(node.id, 0.5 * (*cov + cov->transpose()) + floor);
  }
  return out;
}

Mat3 PsmSlam::uncertaintyFromRobot(int64_t id) const {
  const Mat3 J = composeJacobianB(filter_.keyframePose(id));
  return J * filter_.predictRelative(id).cov * J.transpose();
}

PsmSlamFilterSeed PsmSlam::filterSeed() const {
  return {filter_.exportState(), std::vector<int64_t>(skeleton_.begin(), skeleton_.end())};
}

void PsmSlam::addMapSkeleton(const Pose2& start_pose) {
  // The map's poses are the frame this run continues in: known to about a millimetre, unless the
  // map says how uncertain they were.
  const Mat3 known = covarianceFloor(1e-3, 1e-4);
  std::optional<int64_t> nearest;
  double nearest_distance = 0.0;
  for (const Keyframe& k : keyframes_) {
    if (k.scan.empty()) continue;
    const Pose2 pose = graph_.node(k.id).pose;
    if (skeletonCovers(pose)) continue;
    const auto saved = left_filter_cov_.find(k.id);
    filter_.addIndependentKeyframe(k.id, pose, saved == left_filter_cov_.end() ? known : saved->second + known);
    filter_keyframes_.insert(k.id);
    skeleton_.insert(k.id);
    const double distance = (pose.translation() - start_pose.translation()).norm();
    if (!nearest || distance < nearest_distance) nearest = k.id, nearest_distance = distance;
  }
  if (!nearest) throw std::invalid_argument("no reference scan of the map can be matched");
  filter_.setActiveKeyframe(*nearest);
}

void PsmSlam::addOdometry(const OdometryReading& reading) {
  const OdometryMotionResult result = odometry_.add(reading);
  if (!result.ok()) {
    ++stats_.odometry_rejected;
    return;
  }
  startClock(reading.utime);
  have_odometry_ = true;
  const OdometryMotion& motion = *result.motion;
  const Mat3 Ja = composeJacobianA(pending_motion_, motion.delta), Jb = composeJacobianB(pending_motion_);
  pending_cov_ = Ja * pending_cov_ * Ja.transpose() + Jb * motion.cov * Jb.transpose();
  pending_motion_ = pending_motion_ * motion.delta;
  pending_rotation_ += std::abs(motion.dtheta);
}

void PsmSlam::predictTo(int64_t utime) {
  // Real logs step back in time now and then: such a scan adds no elapsed-time noise.
  const double dt = std::clamp(1e-6 * static_cast<double>(utime - filter_utime_), 0.0, 5.0);
  filter_utime_ = std::max(filter_utime_, utime);
  Pose2 motion = pending_motion_;
  Mat3 Q = pending_cov_;
  if (have_odometry_) {
    Q += Vec3(params_.time_noise_xy * dt, params_.time_noise_xy * dt, params_.time_noise_theta * dt).asDiagonal();
  } else {
    motion = last_scan_motion_;
    Q += Vec3(params_.no_odometry_noise_xy * dt, params_.no_odometry_noise_xy * dt, params_.no_odometry_noise_theta * dt)
             .asDiagonal();
  }
  odometry_still_ = have_odometry_ && pending_motion_.translation().norm() <= params_.stationary_odometry_translation &&
                    pending_rotation_ <= params_.stationary_odometry_rotation;
  filter_.predict(motion, Q);
  pending_motion_ = Pose2();
  pending_cov_.setZero();
  pending_rotation_ = 0.0;
}

std::vector<Pose2> PsmSlam::loopGuesses(const RelativePosePrediction& prior, bool wide) const {
  std::vector<Pose2> guesses{prior.mean};
  const double step = params_.loop_guess_spacing;
  const Mat2 cov = prior.cov.topLeftCorner<2, 2>();
  const double sigma = largestPositionSigma(prior.cov);
  const double k = params_.loop_candidate_sigmas;
  if (!wide || !(step > 0.0) || k * sigma < step) return guesses;
  // A prior wider than PSM's basin: start also from a grid over the k-σ ellipse, keeping the
  // positions from which the robot could see the keyframe's surroundings (within the loop
  // search radius of it), most likely first.
  const Mat2 information = (cov + 1e-9 * Mat2::Identity()).inverse();
  const int n = static_cast<int>(std::ceil(k * sigma / step));
  std::vector<std::pair<double, Vec2>> grid;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const Vec2 offset(i * step, j * step);
      const double d2 = offset.dot(information * offset);
      const Vec2 position = prior.mean.translation() + offset;
      if ((i != 0 || j != 0) && d2 <= k * k && position.norm() <= params_.loop_search_radius) grid.emplace_back(d2, position);
    }
  std::sort(grid.begin(), grid.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [d2, position] : grid) {
    if (guesses.size() >= static_cast<size_t>(std::max(1, params_.loop_max_guesses))) break;
    guesses.emplace_back(position.x(), position.y(), prior.mean.theta);
  }
  return guesses;
}

std::optional<PsmSlam::Observation> PsmSlam::matchKeyframe(const Keyframe& keyframe, const PreparedScan& scan,
                                                           const Pose2& mount,
                                                           const RelativePosePrediction& prior, bool loop_candidate,
                                                           bool wide_search) {
  const std::vector<Pose2> guesses = loop_candidate ? loopGuesses(prior, wide_search) : std::vector<Pose2>{prior.mean};
  std::optional<Observation> best;
  std::vector<Observation> converged;
  for (const Pose2& guess : guesses) {
    const std::optional<RobotFrameMatch> m =
        matchInRobotFrame(matcher_, keyframe.scan, keyframe.laser_mount, scan, mount, guess, params_, loop_candidate);
    if (!m) continue;
    Observation o;
    o.keyframe = keyframe.id;
    o.z = m->z;
    o.R = m->R;
    o.error_index = m->error_index;
    o.overlap = m->overlap;
    if (!best || o.error_index < best->error_index) best = o;
    converged.push_back(o);
  }
  if (best) {
    for (const Observation& o : converged)
      if (between(best->z, o.z).translation().norm() > params_.loop_ambiguity_distance &&
          std::abs(wrapAngle(o.z.theta - best->z.theta)) <= params_.loop_ambiguity_heading &&
          o.error_index <= params_.loop_ambiguity_ratio * best->error_index)
        best->ambiguous = true;
  }
  return best;
}

std::optional<PsmSlam::Observation> PsmSlam::trackReference(const PreparedScan& scan, const Pose2& mount) {
  const int64_t active = filter_.activeKeyframe();
  const Keyframe& reference = keyframe(active);
  const RelativePosePrediction prior = filter_.predictRelative(active);
  std::optional<Observation> best = matchKeyframe(reference, scan, mount, prior, false, false);
  if (!have_odometry_ || !moving_as_before_) return best;
  // Real odometry goes stale for a few scans and then catches up in one jump. When it disagrees
  // with the robot's previous motion, match from that motion too and keep the better match.
  const Pose2 keyframe_pose = filter_.keyframePose(active);
  RelativePosePrediction constant_velocity = prior;
  constant_velocity.mean = between(keyframe_pose, last_scan_pose_ * last_scan_motion_);
  const Pose2 disagreement = between(prior.mean, constant_velocity.mean);
  if (disagreement.translation().norm() < params_.odometry_check_translation &&
      std::abs(disagreement.theta) < params_.odometry_check_rotation)
    return best;
  const std::optional<Observation> other = matchKeyframe(reference, scan, mount, constant_velocity, false, false);
  const bool other_better = other && goodMatch(*other, false) &&
                            (!best || !goodMatch(*best, false) || other->error_index < best->error_index);
  if (!other_better) return best;
  if (best && goodMatch(*best, false)) {
    const Pose2 spread = between(best->z, other->z);
    if (spread.translation().norm() < params_.odometry_check_translation &&
        std::abs(spread.theta) < params_.odometry_check_rotation)
      return best;  // the same answer from both starts: the odometry was fine
  }
  // The odometry step was wrong: widen the prior by how far off it was, so the filter follows the match.
  inflatePriorForMiss(prior, *other);
  return other;
}

void PsmSlam::inflatePriorForMiss(const RelativePosePrediction& prior, const Observation& o) {
  // Rank-one inflation along the innovation ν (keyframe frame), rotated into the robot frame
  // the prediction noise is expressed in: with S' = S + ννᵀ the innovation's χ² becomes
  // c / (1 + c) < 1 (Sherman–Morrison), while directions the miss does not involve (along a
  // corridor, say) keep the odometry's information.
  const Vec3 nu(o.z.x - prior.mean.x, o.z.y - prior.mean.y, wrapAngle(o.z.theta - prior.mean.theta));
  const double c = std::cos(prior.mean.theta), s = std::sin(prior.mean.theta);
  const Vec3 v(c * nu.x() + s * nu.y(), -s * nu.x() + c * nu.y(), nu.z());
  filter_.predict(Pose2(), v * v.transpose());
  ++stats_.odometry_faults;
}

bool PsmSlam::plausibleOdometryFault(const RelativePosePrediction& prior, const Observation& o) const {
  const Pose2 miss = between(prior.mean, o.z);
  if (miss.translation().norm() <= params_.max_odometry_fault_translation &&
      std::abs(miss.theta) <= params_.max_odometry_fault_rotation)
    return true;
  // Farther off, the match must agree with the robot's previous motion (constant velocity):
  // stale odometry that catches up in one jump is off by a whole scan's motion or more.
  if (!moving_as_before_) return false;
  const Pose2 keyframe_pose = filter_.keyframePose(o.keyframe);
  const Pose2 constant_velocity = between(keyframe_pose, last_scan_pose_ * last_scan_motion_);
  const Pose2 disagreement = between(constant_velocity, o.z);
  return disagreement.translation().norm() <= params_.max_odometry_fault_translation &&
         std::abs(disagreement.theta) <= params_.max_odometry_fault_rotation;
}

bool PsmSlam::applyTrackingMatch(const Observation& o, const PreparedScan& scan, const Pose2& mount) {
  const int64_t active = filter_.activeKeyframe();
  const RelativePosePrediction prior = filter_.predictRelative(active);
  if (filter_.update(active, o.z, o.R, params_.chi2_gate).accepted) return true;
  // A good match with the nearby reference outside the gate: the odometry step, not the match,
  // is what is wrong (slip, heading jumps of 5-20 deg between scans on MIT CSAIL). Trust the
  // match and inflate the prior by the miss, within bounds that a tracking match from a prior
  // that far off could still be right, and only if the odometry's pose fits the scans markedly
  // worse: PSM can converge a few decimetres off along a corridor from a right prior, with a
  // tight covariance, and following it puts a wrong loop closure in the graph later.
  if (!plausibleOdometryFault(prior, o)) return false;
  const Keyframe& reference = keyframe(active);
  if (!predictionMisfits(matcher_, reference.scan, reference.laser_mount, scan, mount, prior.mean, o.error_index, params_))
    return false;
  inflatePriorForMiss(prior, o);
  return filter_.update(active, o.z, o.R, params_.chi2_gate).accepted;
}

bool PsmSlam::goodMatch(const Observation& o, bool loop_candidate) const {
  const double max_error = loop_candidate ? params_.loop_max_error_index : params_.max_error_index;
  const double min_overlap = loop_candidate ? params_.loop_min_overlap : params_.min_overlap;
  return std::isfinite(o.error_index) && o.error_index <= max_error && o.overlap >= min_overlap && o.R.allFinite();
}

bool PsmSlam::robotStill(const Observation& tracked) const {
  const Pose2 predicted = filter_.predictRelative(tracked.keyframe).mean;
  const Pose2 difference = between(predicted, tracked.z);
  return difference.translation().norm() <= params_.stationary_match_translation &&
         std::abs(difference.theta) <= params_.stationary_match_rotation;
}

bool PsmSlam::needsNewReference(const std::optional<Observation>& tracked) {
  const Pose2 relative = filter_.predictRelative(filter_.activeKeyframe()).mean;
  size_t* reason = nullptr;
  if (!tracked) reason = &stats_.references_lost;
  else if (relative.translation().norm() > params_.keyframe_distance) reason = &stats_.references_too_far;
  else if (std::abs(relative.theta) > params_.keyframe_angle) reason = &stats_.references_turned;
  else if (tracked->overlap < params_.keyframe_min_overlap) reason = &stats_.references_overlap;
  if (reason) ++*reason;
  return reason != nullptr;
}

bool PsmSlam::isOld(int64_t id) const {
  const int64_t active = filter_.activeKeyframe();
  // A continued map's keyframes and this run's are tied only through matches: always a loop.
  if ((id < map_keyframes_) != (active < map_keyframes_)) return true;
  return active - id >= params_.loop_min_keyframe_gap;
}

std::vector<PsmSlam::Candidate> PsmSlam::referenceCandidates() const {
  const double reuse_distance = params_.reuse_fraction * params_.keyframe_distance;
  const double reuse_angle = params_.reuse_fraction * params_.keyframe_angle;
  const double k = params_.loop_candidate_sigmas;
  std::vector<Candidate> candidates;
  for (const int64_t id : filter_keyframes_) {
    if (id == filter_.activeKeyframe()) continue;
    // Only keyframes that could become the reference again, or old ones (loop closures), are
    // worth a match: the recent chain is already tied to the active keyframe.
    const bool old = isOld(id);
    const double radius = old ? params_.loop_search_radius : reuse_distance;
    const double max_heading = old ? params_.loop_max_heading_difference : reuse_angle;
    // Most keyframes are far beyond any doubt: ruled out on bounds of their spread, the same
    // decision the covariance below would give, without computing it.
    const RelativePoseBound bound = filter_.boundRelative(id);
    const double far_by = std::max(0.0, bound.mean.translation().norm() - radius);
    const double turned_by = std::max(0.0, std::abs(bound.mean.theta) - max_heading);
    if (far_by > k * bound.position_sigma || turned_by > k * bound.heading_sigma) continue;
    const RelativePosePrediction p = filter_.predictRelative(id);
    const double distance = p.mean.translation().norm();
    // Mahalanobis neighbourhood: the robot may be within `radius` of the keyframe if the
    // shortfall along the line to it is within k standard deviations.
    const double shortfall = std::max(0.0, distance - radius);
    if (shortfall > 0.0) {
      const Vec2 u = p.mean.translation() / distance;
      const double variance = u.dot(p.cov.topLeftCorner<2, 2>() * u);
      if (shortfall * shortfall > k * k * variance) continue;
    }
    const double heading_shortfall = std::max(0.0, std::abs(p.mean.theta) - max_heading);
    if (heading_shortfall * heading_shortfall > k * k * p.cov(2, 2)) continue;
    candidates.push_back({id, old, distance + std::abs(p.mean.theta), p});
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
  if (candidates.size() > static_cast<size_t>(std::max(0, params_.max_candidates_per_scan)))
    candidates.resize(static_cast<size_t>(std::max(0, params_.max_candidates_per_scan)));
  return candidates;
}

bool PsmSlam::selectReference(const LaserScan& scan, PreparedScan& prepared, const std::optional<Observation>& tracked,
                              bool& map_matched) {
  const int64_t previous = filter_.activeKeyframe();
  const RelativePosePrediction link = filter_.predictRelative(previous);
  std::vector<Observation> accepted;
  if (tracked) accepted.push_back(*tracked);
  bool loop = false;
  bool wide_search_done = false;
  for (const Candidate& c : referenceCandidates()) {
    ++stats_.candidate_matches;
    if (c.id < map_keyframes_) ++stats_.map_candidate_matches;
    // One wide (many-guess) search per decision: it is the expensive part of loop closure.
    const bool wide = c.old && !wide_search_done;
    wide_search_done = wide_search_done || wide;
    std::optional<Observation> o = matchKeyframe(keyframe(c.id), prepared, scan.laser_pose, c.prediction, c.old, wide);
    if (!o || !goodMatch(*o, c.old)) {
      if (c.old) ++(o ? stats_.loop_poor_matches : stats_.loop_failed_matches);
      continue;
    }
    if (o->ambiguous) {
      ++stats_.loop_ambiguous;
      continue;
    }
    if (!c.old) {
      if (filter_.update(c.id, o->z, o->R, params_.chi2_gate).accepted) accepted.push_back(*o);
      continue;
    }
    if (applyLoopClosure(c, *o, prepared, scan)) {
      accepted.push_back(*o);
      loop = true;
      if (c.id < map_keyframes_) ++stats_.map_loop_closures;
    }
  }
  map_matched = std::any_of(accepted.begin(), accepted.end(), [&](const Observation& o) { return o.keyframe < map_keyframes_; });
  const Observation* reuse = nullptr;
  for (const Observation& o : accepted) {
    if (o.keyframe == previous) continue;
    if (o.z.translation().norm() <= params_.reuse_fraction * params_.keyframe_distance &&
        std::abs(o.z.theta) <= params_.reuse_fraction * params_.keyframe_angle && o.overlap >= params_.keyframe_min_overlap &&
        (!reuse || o.z.translation().norm() < reuse->z.translation().norm()))
      reuse = &o;
  }
  if (reuse) {
    reuseReference(*reuse, accepted);
  } else {
    addKeyframe(scan, std::move(prepared), accepted, link, previous);
  }
  return loop;
}

void PsmSlam::addGraphEdge(int64_t from, int64_t to, const Pose2& z, const Mat3& R, PoseGraphEdgeKind kind) {
  if (kind == PoseGraphEdgeKind::Match && std::abs(to - from) >= params_.loop_min_keyframe_gap) kind = PoseGraphEdgeKind::Loop;
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.measurement = z;
  edge.covariance = 0.5 * (R + R.transpose());
  edge.kind = kind;
  try {
    graph_.addEdge(edge);
  } catch (const std::invalid_argument&) {
    // A degenerate covariance: the filter has used the match; the graph does without it.
  }
}

bool PsmSlam::confirmedByHypothesis(const Pose2& robot, const Pose2& map_pose, double prior_sigma) const {
  // From a prior wider than a look-alike place's extent, two scans a few decimetres apart see the
  // same look-alike: the second closure must come from far enough along the path that the
  // place would have to look alike over that stretch too.
  const bool wide = prior_sigma > params_.loop_wide_prior_sigma;
  for (const LoopHypothesis& h : hypotheses_) {
    if (h.scan == stats_.scans) continue;
    if (wide ? between(h.robot, robot).translation().norm() < params_.loop_wide_confirm_distance
             : stats_.scans - h.scan > static_cast<size_t>(params_.loop_confirm_scans))
      continue;
    // The two closures must agree on how the robot moved in between, as the filter tracked it.
    const Pose2 disagreement = between(between(h.robot, robot), between(h.map_pose, map_pose));
    if (disagreement.translation().norm() <= params_.loop_confirm_translation &&
        std::abs(disagreement.theta) <= params_.loop_confirm_rotation)
      return true;
  }
  return false;
}

bool PsmSlam::beyondVerifyTolerance(const Pose2& a, const Pose2& b) const {
  const Pose2 miss = between(a, b);
  return miss.translation().norm() > params_.loop_verify_translation || std::abs(miss.theta) > params_.loop_verify_rotation;
}

PsmSlam::Verification PsmSlam::verifyWithNeighbours(int64_t closure, const Pose2& closure_z, const PreparedScan& scan,
                                                    const Pose2& mount) {
  // Reference scans of the same pass as the closure's (ids within loop_min_keyframe_gap): their
  // poses relative to it are known well, so the closure predicts closely where each of them
  // must see the robot. Relative poses from the graph, which keeps the marginalised ones too.
  const Pose2 closure_pose = graph_.node(closure).pose;
  std::vector<std::pair<double, std::pair<int64_t, Pose2>>> neighbours;
  const int64_t gap = std::max<int64_t>(1, params_.loop_min_keyframe_gap);
  const int64_t last = static_cast<int64_t>(keyframes_.size()) - 1;
  for (int64_t id = std::max<int64_t>(0, closure - gap + 1); id <= std::min(last, closure + gap - 1); ++id) {
    if (id == closure || !isOld(id) || keyframe(id).scan.empty()) continue;
    const Pose2 expected = between(graph_.node(id).pose, closure_pose) * closure_z;
    if (expected.translation().norm() > params_.loop_search_radius ||
        std::abs(expected.theta) > params_.loop_max_heading_difference)
      continue;
    neighbours.push_back({expected.translation().norm(), {id, expected}});
  }
  std::sort(neighbours.begin(), neighbours.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  if (neighbours.size() > static_cast<size_t>(std::max(0, params_.max_candidates_per_scan)))
    neighbours.resize(static_cast<size_t>(std::max(0, params_.max_candidates_per_scan)));
  bool agreed = false;
  for (const auto& [distance, neighbour] : neighbours) {
    const auto& [id, expected] = neighbour;
    const std::optional<Observation> o = matchKeyframe(keyframe(id), scan, mount, {expected, Mat3::Zero()}, true, false);
    if (!o || !goodMatch(*o, true)) continue;
    if (beyondVerifyTolerance(expected, o->z)) return Verification::Refuted;
    agreed = true;
  }
  return agreed ? Verification::Agreed : Verification::NoEvidence;
}

bool PsmSlam::refutedWithoutMedianFilter(const Candidate& c, const Observation& o, const LaserScan& raw) {
  const Keyframe& reference = keyframe(c.id);
  if (!params_.loop_check_unfiltered || !params_.psm.median_filter || reference.raw.ranges.empty()) return false;
  PsmParams unfiltered = params_.psm;
  unfiltered.median_filter = false;
  std::optional<PreparedScan> reference_scan = prepareMatchableScan(reference.raw, unfiltered);
  std::optional<PreparedScan> scan = prepareMatchableScan(raw, unfiltered);
  if (!reference_scan || !scan) return false;
  const Keyframe unfiltered_reference{reference.id, reference.utime, reference.laser_mount, std::move(*reference_scan), {}};
  const std::optional<Observation> u = matchKeyframe(unfiltered_reference, *scan, raw.laser_pose, c.prediction, true, false);
  if (!u || !goodMatch(*u, true) || u->ambiguous) return false;
  if (!beyondVerifyTolerance(o.z, u->z)) return false;
  // Along a featureless corridor the raw match may just stay where the prior put it: only a
  // markedly better fit of the raw ranges than the closure's pose gives refutes it.
  return errorIndexAt(matcher_, unfiltered_reference.scan, reference.laser_mount, *scan, raw.laser_pose, o.z) >
         params_.loop_unfiltered_fit_ratio * u->error_index;
}

bool PsmSlam::applyLoopClosure(const Candidate& c, const Observation& o, const PreparedScan& scan, const LaserScan& raw) {
  const Pose2 mount = raw.laser_pose;
  if (refutedWithoutMedianFilter(c, o, raw)) {
    ++stats_.loop_unfiltered_refuted;
    return false;
  }
  double gate = params_.loop_chi2_gate;
  const double prior_sigma = largestPositionSigma(c.prediction.cov);
  if (prior_sigma > params_.loop_confirm_sigma) {
    // A wide prior lets an aliased match (a look-alike corridor) through the χ² gate. Two
    // independent checks: the closure's neighbouring reference scans must not see the robot
    // elsewhere, and a second closure from a later scan must agree on the motion in between.
    const Pose2 robot = filter_.robotPose(), map_pose = filter_.keyframePose(c.id) * o.z;
    const Verification verification = verifyWithNeighbours(c.id, o.z, scan, mount);
    if (verification == Verification::Refuted) {
      ++stats_.loop_refuted;
      return false;
    }
    // Without a neighbour's say the closure rests on the robot being near this reference scan
    // at all. When the prior is wide (loop_unverified_max_extent, within the disc a loop search
    // examines), the robot may well be somewhere else that merely looks alike.
    if (verification == Verification::NoEvidence &&
        params_.loop_candidate_sigmas * prior_sigma > params_.loop_unverified_max_extent) {
      ++stats_.loop_unverified;
      return false;
    }
    if (!confirmedByHypothesis(robot, map_pose, prior_sigma)) {
      hypotheses_.push_back({stats_.scans, robot, map_pose});
      if (hypotheses_.size() > 32) hypotheses_.erase(hypotheses_.begin());
      ++stats_.loop_unconfirmed;
      return false;
    }
    gate = params_.loop_confirmed_chi2_gate;
  }
  if (!filter_.update(c.id, o.z, o.R, gate).accepted) {
    ++stats_.loop_gate_rejections;
    return false;
  }
  ++stats_.loop_closures;
  return true;
}

void PsmSlam::reuseReference(const Observation& chosen, const std::vector<Observation>& accepted) {
  for (const Observation& o : accepted) {
    if (o.keyframe == chosen.keyframe) continue;
    const auto [z, R] = composeThroughScan(o.z, o.R, chosen.z, chosen.R);
    addGraphEdge(o.keyframe, chosen.keyframe, z, R, PoseGraphEdgeKind::Match);
  }
  filter_.setActiveKeyframe(chosen.keyframe);
  ++stats_.reference_reuses;
}

void PsmSlam::addKeyframe(const LaserScan& scan, PreparedScan prepared, const std::vector<Observation>& accepted,
                          const std::optional<RelativePosePrediction>& link, int64_t previous) {
  const int64_t id = static_cast<int64_t>(keyframes_.size());
  filter_.addKeyframe(id);
  filter_keyframes_.insert(id);
  graph_.addNode({id, scan.utime, filter_.robotPose()});
  // The link to the previous reference is the filter's estimate of the relative pose (odometry
  // and the tracking match fused), not the raw match: along a corridor the match leaves the
  // translation free and only the odometry in the filter fixes it, which the graph must keep.
  for (const Observation& o : accepted)
    if (!link || o.keyframe != previous) addGraphEdge(o.keyframe, id, o.z, o.R, PoseGraphEdgeKind::Match);
  if (link && previous >= 0)
    addGraphEdge(previous, id, link->mean, link->cov + covarianceFloor(1e-3, 1e-3), PoseGraphEdgeKind::Odometry);
  keyframes_.push_back({id, scan.utime, scan.laser_pose, std::move(prepared), scan});
  ++stats_.keyframes;
  marginaliseOldKeyframes();
}

void PsmSlam::marginaliseKeyframe(int64_t id) {
  graph_.setPose(id, filter_.keyframePose(id));
  left_filter_cov_[id] = filter_.keyframeCovariance(id);
  filter_.removeKeyframe(id);
  filter_keyframes_.erase(id);
  skeleton_.erase(id);
}

bool PsmSlam::skeletonCovers(const Pose2& pose) const {
  return std::any_of(skeleton_.begin(), skeleton_.end(), [&](int64_t kept) {
    const Pose2 other = filter_.keyframePose(kept);
    return (other.translation() - pose.translation()).norm() < params_.skeleton_spacing &&
           std::abs(wrapAngle(other.theta - pose.theta)) < params_.skeleton_heading;
  });
}

void PsmSlam::marginaliseOldKeyframes() {
  // Keyframes that have just left the recent window: keep one if it adds to the skeleton.
  const int64_t window_start = filter_.activeKeyframe() - std::max(1, params_.filter_window);
  while (!filter_keyframes_.empty()) {
    const auto candidate = std::find_if(filter_keyframes_.begin(), filter_keyframes_.end(),
                                        [&](int64_t id) { return id < window_start && !skeleton_.count(id); });
    if (candidate == filter_keyframes_.end()) break;
    const int64_t id = *candidate;
    if (skeletonCovers(filter_.keyframePose(id))) {
      marginaliseKeyframe(id);
    } else {
      skeleton_.insert(id);
    }
  }
  while (filter_keyframes_.size() > std::max<size_t>(2, params_.max_filter_keyframes)) {
    auto it = filter_keyframes_.begin();
    if (*it == filter_.activeKeyframe()) ++it;
    const int64_t id = *it;
    marginaliseKeyframe(id);
  }
}

void PsmSlam::syncGraphFromFilter() {
  // Keyframes still in the filter take its (loop-corrected) estimate; the ones marginalised
  // earlier move rigidly with the filter keyframe before them, so that the optimiser starts
  // from a consistent guess instead of a map torn at every marginalised keyframe.
  // The first node defines the frame and stays where it is. A filter resumed from a snapshot
  // holds it only as uncertain as the robot sees it, so a loop closure to it would otherwise move
  // the whole map by the robot's drift instead of moving the robot.
  Pose2 correction;  // new ⊕ ⊖old of the latest filter keyframe passed
  for (const PoseGraphNode& node : std::vector<PoseGraphNode>(graph_.nodes())) {
    if (node.id == 0) continue;
    if (map_frozen_ && node.id < map_keyframes_) continue;  // where the map has it
    if (filter_.hasKeyframe(node.id)) {
      const Pose2 updated = filter_.keyframePose(node.id);
      correction = updated * node.pose.inverse();
      graph_.setPose(node.id, updated);
    } else {
      graph_.setPose(node.id, correction * node.pose);
    }
  }
}

PoseGraphOptimizationSummary PsmSlam::optimize() {
  syncGraphFromFilter();
  PoseGraphOptimizerOptions options = params_.graph;
  if (map_frozen_) options.fixed_below = map_keyframes_;
  const PoseGraphOptimizationSummary summary = optimizePoseGraph(graph_, options);
  if (summary.solved) {
    std::unordered_map<int64_t, Pose2> poses;
    for (const int64_t id : filter_keyframes_) poses[id] = graph_.node(id).pose;
    filter_.setKeyframePoses(poses);
  }
  ++stats_.optimizations;
  stats_.optimization_seconds += summary.seconds;
  stats_.last_optimization_seconds = summary.seconds;
  stats_.rejected_loop_edges += summary.rejected_loops;
  keyframes_at_last_optimization_ = static_cast<int64_t>(keyframes_.size());
  loop_pending_ = false;
  return summary;
}

void PsmSlam::record(int64_t utime, PsmSlamScanResult& result) {
  const Pose2 robot = filter_.robotPose();
  const int64_t anchor = filter_.activeKeyframe();
  TrajectoryRecord r;
  r.utime = utime;
  r.anchor = anchor;
  r.relative = anchor >= 0 ? between(filter_.keyframePose(anchor), robot) : robot;
  r.cov = filter_.robotCovariance();
  records_.push_back(r);
  result.pose = {utime, robot, r.cov};
  const bool newest = !keyframes_.empty() && anchor == keyframes_.back().id;
  result.anchor = {utime, anchor, r.relative, result.new_keyframe && newest};
  last_scan_motion_ = between(last_scan_pose_, robot);
  last_scan_pose_ = robot;
  stats_.filter_flushes = filter_.flushCount();
}

PsmSlamScanResult PsmSlam::addScan(const LaserScan& scan) {
  ++stats_.scans;
  PsmSlamScanResult result;
  startClock(scan.utime);
  // The previous scan's motion says where the robot goes next only over one scan's interval: not
  // after a restart or a stretch of lost scans (seconds in which the robot drove on).
  moving_as_before_ = last_scan_utime_ && scan.utime - *last_scan_utime_ <= kMaxConstantVelocityInterval;
  after_downtime_ = after_downtime_ || (last_scan_utime_ && !moving_as_before_);
  last_scan_utime_ = scan.utime;
  predictTo(scan.utime);
  std::optional<PreparedScan> prepared = prepareMatchableScan(scan, params_.psm);
  if (!prepared) {
    ++stats_.unusable_scans;
    record(scan.utime, result);
    return result;
  }
  result.usable = true;
  if (keyframes_.empty()) {
    addKeyframe(scan, std::move(*prepared), {}, std::nullopt, -1);
    result.new_keyframe = true;
    record(scan.utime, result);
    return result;
  }
  std::optional<Observation> tracked = trackReference(*prepared, scan.laser_pose);
  // After seconds without scans the robot has moved on, and the match with its reference overlaps
  // less: it is judged as a loop closure's (a stricter error, a looser overlap) rather than thrown
  // away for a new reference tied by odometry alone (docs/maps.md, "The downtime").
  const bool after_downtime = std::exchange(after_downtime_, false);
  if (tracked && (goodMatch(*tracked, false) || (after_downtime && goodMatch(*tracked, true)))) {
    if (odometry_still_ && robotStill(*tracked)) {
      result.held = true;
      ++stats_.held_scans;
      result.map_matched = tracked->keyframe < map_keyframes_;
    } else if (applyTrackingMatch(*tracked, *prepared, scan.laser_pose)) {
      result.tracked = true;
      ++stats_.tracked_scans;
      result.map_matched = tracked->keyframe < map_keyframes_;
    } else {
      ++stats_.gate_rejections;
      tracked.reset();
    }
  } else {
    ++stats_.match_failures;
    tracked.reset();
  }
  if (needsNewReference(tracked)) {
    const size_t keyframes_before = keyframes_.size();
    result.loop_closed = selectReference(scan, *prepared, tracked, result.map_matched);
    result.new_keyframe = keyframes_.size() > keyframes_before;
    if (result.loop_closed) loop_pending_ = true;
  }
  if (loop_pending_ && params_.optimize_on_loop &&
      static_cast<int64_t>(keyframes_.size()) - keyframes_at_last_optimization_ >=
          params_.min_keyframes_between_optimizations) {
    joinBackgroundRefinement();
    optimize();
    startBackgroundRefinement();
    result.optimized = true;
  }
  record(scan.utime, result);
  return result;
}

std::vector<PoseStamped> PsmSlam::trajectory() const {
  std::vector<PoseStamped> poses;
  poses.reserve(records_.size());
  for (const TrajectoryRecord& r : records_) {
    Pose2 pose = r.relative;
    if (r.anchor >= 0)
      pose = (filter_.hasKeyframe(r.anchor) ? filter_.keyframePose(r.anchor) : graph_.node(r.anchor).pose) * r.relative;
    poses.push_back({r.utime, pose, r.cov});
  }
  return poses;
}

}  // namespace polarslam
