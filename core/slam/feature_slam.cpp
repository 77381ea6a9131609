#include "slam/feature_slam.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <tuple>

#include "odometry/odometry_history.hpp"
#include "slam/feature_models.hpp"
#include "sonar/feature_frames.hpp"

namespace polarslam {
namespace {

constexpr int64_t kNever = std::numeric_limits<int64_t>::max();

int64_t micros(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e6)); }


/// Finite, symmetric and positive definite (top-left n × n block).
bool usableCovariance(const Mat3& cov, int n) {
  const Eigen::MatrixXd block = cov.topLeftCorner(n, n);
  if (!block.allFinite()) return false;
  if (!block.isApprox(block.transpose(), 1e-6) && (block - block.transpose()).cwiseAbs().maxCoeff() > 1e-12) return false;
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (block + block.transpose()));
  return llt.info() == Eigen::Success;
}

Mat3 pad(const Mat2& m) {
  Mat3 out = Mat3::Zero();
  out.topLeftCorner<2, 2>() = m;
  return out;
}

Mat3 padRows(const Mat23& m) {
  Mat3 out = Mat3::Zero();
  out.topRows<2>() = m;
  return out;
}

/// Unit direction along a map line with normal angle α.
Vec2 lineDirection(double alpha) { return {-std::sin(alpha), std::cos(alpha)}; }

/// Robot-frame line endpoints into the map frame, as positions along the map line.
std::pair<double, double> extentAlong(double alpha, const Observation& obs, const Pose2& pose) {
  const Vec2 u = lineDirection(alpha);
  const double a = pose.transform(obs.endpoint_a).dot(u), b = pose.transform(obs.endpoint_b).dot(u);
  return {std::min(a, b), std::max(a, b)};
}

/// Map-frame feature parameters from an observation, through g() of App. B.
struct InitResult {
  Vec3 y = Vec3::Zero();
  Mat3 G_x = Mat3::Zero(), G_z = Mat3::Zero();
};
InitResult initFrom(const Pose2& pose, const Observation& obs) {
  InitResult r;
  switch (obs.kind) {
    case MapFeatureKind::Line: {
      const LineInitModel m = initLine(pose, obs.z.head<2>());
      r.y.head<2>() = m.y;
      r.G_x = padRows(m.G_x);
      r.G_z = pad(m.G_z);
      break;
    }
    case MapFeatureKind::Point: {
      const PointInitModel m = initPoint(pose, obs.z.head<2>());
      r.y.head<2>() = m.y;
      r.G_x = padRows(m.G_x);
      r.G_z = pad(m.G_z);
      break;
    }
    case MapFeatureKind::Corner: {
      const CornerInitModel m = initCorner(pose, obs.z);
      r.y = m.y;
      r.G_x = m.G_x;
      r.G_z = m.G_z;
      break;
    }
  }
  return r;
}

/// Upper bound of the innovation's standard deviation per row: the std of a sum of (possibly
/// correlated) terms is at most the sum of their stds.
bool passesQuickGate(const LinearizedObservation& lin, const Vec3& robot_sigma, const Vec3& feature_sigma,
                     double gate) {
  for (int k = 0; k < lin.dim; ++k) {
    const double bound = lin.H_x.row(k).cwiseAbs().dot(robot_sigma) + lin.H_y.row(k).cwiseAbs().dot(feature_sigma) +
                         std::sqrt(std::max(0.0, lin.R(k, k)));
    if (lin.innovation(k) * lin.innovation(k) > gate * bound * bound) return false;
  }
  return true;
}

}  // namespace

OdometryModelParams FeatureSlamParams::defaultOdometry() {
  OdometryModelParams p;
  p.wheels.wheelbase = 0.5;
  p.wheels.k_left = 2e-5;
  p.wheels.k_right = 2e-5;
  return p;
}

std::vector<Observation> observationsFrom(const FeatureSet& base, const FeatureSlamParams& params, int* rejected) {
  std::vector<Observation> out;
  int bad = 0;
  const double scale = params.observation_cov_scale;
  for (const LineFeature& l : base.lines) {
    if (!std::isfinite(l.alpha) || !std::isfinite(l.d) || !usableCovariance(pad(l.cov), 2) ||
        !l.endpoint_a.allFinite() || !l.endpoint_b.allFinite()) {
      ++bad;
      continue;
    }
    if (std::abs(l.d) < params.min_line_distance) continue;
    Observation o;
    o.kind = MapFeatureKind::Line;
    o.z = {wrapAngle(l.d < 0.0 ? l.alpha + std::numbers::pi : l.alpha), std::abs(l.d), 0.0};
    o.R = pad(l.cov) * scale;
    if (l.d < 0.0) o.R(0, 1) = o.R(1, 0) = -o.R(0, 1);
    o.dim = 2;
    o.source = l.source;
    o.endpoint_a = l.endpoint_a;
    o.endpoint_b = l.endpoint_b;
    out.push_back(o);
  }
  for (const CornerFeature& c : base.corners) {
    const bool unknown = c.cov.allFinite() && cornerOrientationUnknown(c.cov);
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.gamma) ||
        !usableCovariance(c.cov, unknown ? 2 : 3)) {
      ++bad;
      continue;
    }
    const PolarCorner polar = cornerToPolar({c.x, c.y, wrapAngle(c.gamma)});
    if (polar.z.y() < params.min_corner_range) continue;
    Observation o;
    o.kind = MapFeatureKind::Corner;
    o.z = polar.z;
    Mat3 cov = c.cov;
    if (unknown) {
      cov.row(2).setZero();
      cov.col(2).setZero();
    }
    o.R = polar.J * cov * polar.J.transpose() * scale;
    if (unknown) o.R(2, 2) = kUnknownAngleVariance;
    o.dim = unknown ? 2 : 3;
    o.convex = c.convex;
    o.source = c.source;
    out.push_back(o);
  }
  for (const PointFeature& p : base.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !usableCovariance(pad(p.cov), 2)) {
      ++bad;
      continue;
    }
    Observation o;
    o.kind = MapFeatureKind::Point;
    o.z = {p.x, p.y, 0.0};
    o.R = pad(p.cov) * scale;
    o.dim = 2;
    o.source = p.source;
    out.push_back(o);
  }
  if (rejected) *rejected += bad;
  return out;
}

FeatureSlam::FeatureSlam(FeatureSlamParams params) : params_(params) { validate(params_.odometry); }

void FeatureSlam::reject(long& counter, const std::string& reason) {
  ++counter;
  ++stats_.reject_reasons[reason];
}

std::string FeatureSlam::addOdometry(const OdometryReading& reading) {
  if (!finitePose(reading.pose) || !std::isfinite(reading.left_travel) || !std::isfinite(reading.right_travel)) {
    reject(stats_.rejected_odometry, "odometry: non-finite value");
    return "odometry: non-finite value";
  }
  if (reading.utime <= last_odometry_utime_) {
    const std::string why = reading.utime < last_odometry_utime_ ? "odometry: time went backwards"
                                                                  : "odometry: repeated time stamp";
    reject(stats_.rejected_odometry, why);
    return why;
  }
  last_odometry_utime_ = reading.utime;
  stream_time_ = std::max(stream_time_, reading.utime);
  odometry_queue_.push_back(reading);
  ++stats_.odometry;
  process(false);
  return {};
}

std::string FeatureSlam::addFeatures(const FeatureSet& features) {
  if (features.utime < last_feature_utime_ || features.utime < filter_time_) {
    const std::string why = features.utime < filter_time_ ? "features: older than the filter" : "features: out of order";
    reject(stats_.rejected_sets, why);
    return why;
  }
  if (!finitePose(features.sensor_pose)) {
    reject(stats_.rejected_sets, "features: non-finite sensor pose");
    return "features: non-finite sensor pose";
  }
  last_feature_utime_ = features.utime;
  stream_time_ = std::max(stream_time_, features.utime);
  feature_queue_.push_back(toBaseFrame(features));
  ++stats_.feature_sets;
  process(false);
  return {};
}

std::string FeatureSlam::requestAnchors(int64_t utime) {
  if (utime < filter_time_ || (!anchor_queue_.empty() && utime < anchor_queue_.back())) {
    reject(stats_.rejected_sets, "anchors: requested for a time already processed");
    return "anchors: requested for a time already processed";
  }
  stream_time_ = std::max(stream_time_, utime);
  last_scan_utime_ = std::max(last_scan_utime_, utime);
  anchor_queue_.push_back(utime);
  process(false);
  return {};
}

void FeatureSlam::flush() { process(true); }

void FeatureSlam::process(bool flushing) {
  const int64_t latency = micros(params_.latency_s), max_lag = micros(params_.max_feature_lag_s);
  auto waited = [&](int64_t t) { return flushing || stream_time_ - t >= latency; };
  // Whether a feature set older than t can no longer come: `latency_s` for sets nobody announced;
  // an announced scan's set (feature_set_per_scan) is waited for up to max_feature_lag_s.
  auto featureStreamPast = [&](int64_t t) {
    const bool scan_set_due = params_.feature_set_per_scan && last_scan_utime_ > last_feature_utime_;
    if (flushing || !scan_set_due) return waited(t);
    if (stream_time_ - t < max_lag) return false;
    ++stats_.gave_up_waiting;
    return true;
  };
  while (true) {
    const int64_t t_odo = odometry_queue_.empty() ? kNever : odometry_queue_.front().utime;
    const int64_t t_feat = feature_queue_.empty() ? kNever : feature_queue_.front().utime;
    const int64_t t_anchor = anchor_queue_.empty() ? kNever : anchor_queue_.front();
    const int64_t t = std::min({t_odo, t_feat, t_anchor});
    if (t == kNever) return;
    if (t_odo == t) {  // odometry first on ties: a feature set at t sees the motion up to t
      // Later feature sets cannot be older than the newest one received.
      if (!(last_feature_utime_ >= t_odo || featureStreamPast(t_odo))) return;
      predictTo(odometry_queue_.front());
      poses_.push_back({t_odo, state_.pose(), state_.poseCovariance()});
      odometry_queue_.pop_front();
      continue;
    }
    if (t_feat == t) {
      if (!(!odometry_queue_.empty() || waited(t_feat))) return;
      advanceTo(t_feat);
      const FeatureSet set = std::move(feature_queue_.front());
      feature_queue_.pop_front();
      processFeatures(set);
      continue;
    }
    if (!((!odometry_queue_.empty() && last_feature_utime_ >= t_anchor) || featureStreamPast(t_anchor))) return;
    advanceTo(t_anchor);
    anchor_queue_.pop_front();
    emitAnchors(t_anchor);
  }
}

void FeatureSlam::advanceTo(int64_t t) {
  filter_time_ = std::max(filter_time_, t);
  if (!last_reading_ || odometry_queue_.empty() || t <= last_reading_->utime) return;
  predictTo(interpolateOdometry(*last_reading_, odometry_queue_.front(), t));
}

void FeatureSlam::predictTo(const OdometryReading& reading) {
  filter_time_ = std::max(filter_time_, reading.utime);
  if (!last_reading_) {
    last_reading_ = reading;
    return;
  }
  const OdometryMotionResult result = odometryMotion(*last_reading_, reading, params_.odometry);
  if (result.ok()) {
    state_.predict(*result.motion);
    last_reading_ = reading;
    return;
  }
  reject(stats_.rejected_odometry, "odometry: " + result.error.substr(0, result.error.find(' ', 20)));
  if (result.fault == OdometryFault::TooLarge) last_reading_ = reading;
}

std::optional<LinearizedObservation> FeatureSlam::linearize(int feature, const Observation& obs, double* side) const {
  const Pose2 pose = state_.pose();
  const Vec3 y = state_.featureMean(feature);
  LinearizedObservation lin;
  lin.feature = feature;
  lin.dim = obs.dim;
  lin.R = obs.R;
  switch (obs.kind) {
    case MapFeatureKind::Line: {
      const LineObservationModel m = observeLine(pose, y.head<2>());
      if (side) *side = m.s;
      lin.innovation = {wrapAngle(obs.z.x() - m.z.x()), obs.z.y() - m.z.y(), 0.0};
      lin.H_x = padRows(m.H_x);
      lin.H_y = pad(m.H_y);
      break;
    }
    case MapFeatureKind::Point: {
      const PointObservationModel m = observePoint(pose, y.head<2>());
      lin.innovation = {obs.z.x() - m.z.x(), obs.z.y() - m.z.y(), 0.0};
      lin.H_x = padRows(m.H_x);
      lin.H_y = pad(m.H_y);
      break;
    }
    case MapFeatureKind::Corner: {
      const CornerObservationModel m = observeCorner(pose, y);
      if (!(m.z.y() > 0.0)) return std::nullopt;
      lin.innovation = {wrapAngle(obs.z.x() - m.z.x()), obs.z.y() - m.z.y(), wrapAngle(obs.z.z() - m.z.z())};
      lin.H_x = m.H_x;
      lin.H_y = m.H_y;
      if (obs.dim == 2) {
        lin.H_x.row(2).setZero();
        lin.H_y.row(2).setZero();
        lin.innovation.z() = 0.0;
      }
      break;
    }
  }
  return lin;
}

double FeatureSlam::viewAngle(const FeatureInfo& info, const Vec2& position) const {
  const Vec2 to_robot = state_.pose().translation() - position;
  return wrapAngle(std::atan2(to_robot.y(), to_robot.x()) - info.view_ref);
}

namespace {

/// The direction `relative`, shifted by ±2π to where it lies closest to the arc [lo, hi], and
/// its distance from the arc.
std::pair<double, double> nearestOnArc(double lo, double hi, double relative) {
  double best = relative, best_gap = std::numeric_limits<double>::infinity();
  for (double shift : {0.0, 2.0 * std::numbers::pi, -2.0 * std::numbers::pi}) {
    const double r = relative + shift, gap = std::max({0.0, lo - r, r - hi});
    if (gap < best_gap) {
      best_gap = gap;
      best = r;
    }
  }
  return {best, best_gap};
}

}  // namespace

void FeatureSlam::widenView(FeatureInfo& info, double relative) {
  const double r = nearestOnArc(info.view_lo, info.view_hi, relative).first;
  info.view_lo = std::min(info.view_lo, r);
  info.view_hi = std::max(info.view_hi, r);
}

bool FeatureSlam::compatible(const FeatureInfo& info, const Observation& obs, double side, const Vec2& position) const {
  if (info.kind != obs.kind) return false;
  if (obs.kind == MapFeatureKind::Line) return side == info.side;
  if (obs.kind == MapFeatureKind::Corner && info.convex != obs.convex) return false;
  return nearestOnArc(info.view_lo, info.view_hi, viewAngle(info, position)).second <= params_.max_view_change;
}

void FeatureSlam::growExtent(FeatureInfo& info, const Vec2& map_line, const Observation& obs, const Pose2& pose) const {
  const auto [a, b] = extentAlong(map_line.x(), obs, pose);
  info.t_min = std::min(info.t_min, a);
  info.t_max = std::max(info.t_max, b);
}

void FeatureSlam::processFeatures(const FeatureSet& set) {
  const auto start = std::chrono::steady_clock::now();
  int bad = 0;
  const std::vector<Observation> observations = observationsFrom(set, params_, &bad);
  if (bad > 0) {
    stats_.rejected_features += bad;
    stats_.reject_reasons["features: non-finite or invalid covariance"] += bad;
  }
  stats_.observations += static_cast<long>(observations.size());

  const Pose2 pose = state_.pose();
  const Mat3 P_rr = state_.poseCovariance();
  const Vec3 robot_sigma = P_rr.diagonal().cwiseMax(0.0).cwiseSqrt();
  std::vector<std::vector<AssociationCandidate>> candidates(observations.size());
  std::vector<bool> near_existing(observations.size(), false);
  const auto& features = state_.features();
  for (size_t i = 0; i < observations.size(); ++i) {
    const Observation& obs = observations[i];
    const double new_gate = chiSquaredGate(obs.dim, params_.new_feature_probability);
    const double gate = chiSquaredGate(obs.dim, params_.association.gate_probability);
    for (size_t j = 0; j < features.size(); ++j) {
      if (features[j].kind != obs.kind) continue;
      double side = 1.0;
      const auto lin = linearize(static_cast<int>(j), obs, &side);
      if (!lin || !compatible(info_[j], obs, side, state_.featureMean(static_cast<int>(j)).head<2>())) continue;
      const Vec3 feature_sigma = state_.featureCovariance(static_cast<int>(j)).diagonal().cwiseMax(0.0).cwiseSqrt();
      if (!passesQuickGate(*lin, robot_sigma, feature_sigma, new_gate)) continue;
      const double d2 = mahalanobis2(state_, *lin);
      if (d2 > new_gate) continue;
      if (obs.kind == MapFeatureKind::Line) {
        const auto [a, b] = extentAlong(state_.featureMean(static_cast<int>(j)).x(), obs, pose);
        const double gap = std::max({0.0, a - info_[j].t_max, info_[j].t_min - b});
        if (gap > params_.max_line_extent_gap) continue;
      }
      near_existing[i] = true;
      if (d2 <= gate) candidates[i].push_back({*lin, d2});
    }
    std::sort(candidates[i].begin(), candidates[i].end(),
              [](const AssociationCandidate& a, const AssociationCandidate& b) { return a.d2 < b.d2; });
  }

  const AssociationResult assoc = associate(state_, candidates, params_.association);
  stats_.jcbb_budget_exhausted += assoc.budget_exhausted;
  std::vector<LinearizedObservation> pairs;
  std::vector<size_t> paired_obs;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (assoc.pairing[i] < 0) continue;
    pairs.push_back(candidates[i][static_cast<size_t>(assoc.pairing[i])].lin);
    paired_obs.push_back(i);
  }
  if (!pairs.empty()) {
    if (state_.update(pairs)) {
      const Pose2 updated = state_.pose();
      for (size_t k = 0; k < pairs.size(); ++k) {
        FeatureInfo& info = info_[static_cast<size_t>(pairs[k].feature)];
        ++info.observations;
        info.last_utime = set.utime;
        matches_.emplace_back(set.utime, info.id);
        const Vec2 y = state_.featureMean(pairs[k].feature).head<2>();
        if (info.kind == MapFeatureKind::Line)
          growExtent(info, y, observations[paired_obs[k]], updated);
        else
          widenView(info, viewAngle(info, y));
      }
      stats_.paired += static_cast<long>(pairs.size());
    } else {
      ++stats_.failed_updates;
    }
  }

  std::vector<const Observation*> unmatched;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (assoc.pairing[i] >= 0) continue;
    if (assoc.ambiguous[i]) {
      ++stats_.ambiguous;
    } else if (near_existing[i]) {
      ++stats_.near_existing;
    } else {
      unmatched.push_back(&observations[i]);
    }
  }
  handleUnmatched(unmatched, set.utime);
  expireTentatives(set.utime);
  ++stats_.updates;
  stats_.update_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void FeatureSlam::handleUnmatched(const std::vector<const Observation*>& unmatched, int64_t utime) {
  const Pose2 pose = state_.pose();
  const Mat3 relative = params_.tentative_pose_sigma.cwiseAbs2().asDiagonal();
  std::vector<bool> used(tentatives_.size(), false);
  std::vector<std::pair<size_t, const Observation*>> promote_with;
  for (const Observation* obs : unmatched) {
    const InitResult init = initFrom(pose, *obs);
    const Mat3 P_obs = init.G_z * obs->R * init.G_z.transpose() + init.G_x * relative * init.G_x.transpose();
    double side = 1.0;
    if (obs->kind == MapFeatureKind::Line) side = observeLine(pose, init.y.head<2>()).s;
    int best = -1;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < tentatives_.size(); ++k) {
      const Tentative& t = tentatives_[k];
      if (used[k] || t.info.kind != obs->kind) continue;
      if (!compatible(t.info, *obs, obs->kind == MapFeatureKind::Line ? observeLine(pose, t.y.head<2>()).s : 1.0,
                      t.y.head<2>()))
        continue;
      const int n = obs->kind == MapFeatureKind::Corner && obs->dim == 3 && t.gamma_known ? 3 : 2;
      const Vec3 nu = observationDifference(obs->kind, init.y, t.y);
      const Eigen::MatrixXd S = (P_obs + t.P).topLeftCorner(n, n);
      const Eigen::LLT<Eigen::MatrixXd> llt(S);
      if (llt.info() != Eigen::Success) continue;
      const Eigen::VectorXd v = nu.head(n);
      const double d2 = v.dot(llt.solve(v));
      if (d2 <= chiSquaredGate(n, params_.tentative_gate_probability) && d2 < best_d2) {
        best_d2 = d2;
        best = static_cast<int>(k);
      }
    }
    if (best < 0) {
      Tentative t;
      t.info.id = next_id_++;
      t.info.kind = obs->kind;
      t.info.first_utime = t.info.last_utime = utime;
      t.info.convex = obs->convex;
      t.info.side = side;
      if (obs->kind != MapFeatureKind::Line) {
        const Vec2 to_robot = pose.translation() - init.y.head<2>();
        t.info.view_ref = std::atan2(to_robot.y(), to_robot.x());
      }
      if (obs->kind == MapFeatureKind::Line) std::tie(t.info.t_min, t.info.t_max) = extentAlong(init.y.x(), *obs, pose);
      t.info.observations = 1;
      t.y = init.y;
      t.P = P_obs;
      t.gamma_known = obs->dim == 3;
      tentatives_.push_back(t);
      used.push_back(true);
      ++stats_.tentative_started;
      if (params_.confirm_observations <= 1) promote_with.emplace_back(tentatives_.size() - 1, obs);
      continue;
    }
    Tentative& t = tentatives_[static_cast<size_t>(best)];
    used[static_cast<size_t>(best)] = true;
    ++t.info.observations;
    t.info.last_utime = utime;
    t.y = init.y;
    t.P = P_obs;
    t.gamma_known = t.gamma_known || obs->dim == 3;
    if (obs->kind != MapFeatureKind::Line) widenView(t.info, viewAngle(t.info, init.y.head<2>()));
    if (obs->kind == MapFeatureKind::Line) {
      const auto [a, b] = extentAlong(init.y.x(), *obs, pose);
      t.info.t_min = std::min(t.info.t_min, a);
      t.info.t_max = std::max(t.info.t_max, b);
    }
    if (t.info.observations >= params_.confirm_observations) promote_with.emplace_back(static_cast<size_t>(best), obs);
  }
  // Promote (highest index first, so the erase keeps the other indices valid).
  std::sort(promote_with.begin(), promote_with.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [k, obs] : promote_with) {
    promote(tentatives_[k], *obs);
    tentatives_.erase(tentatives_.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

void FeatureSlam::promote(Tentative& t, const Observation& obs) {
  const Pose2 pose = state_.pose();
  const InitResult init = initFrom(pose, obs);
  FeatureInfo info = t.info;
  if (obs.kind == MapFeatureKind::Line) {
    // The extent was measured along the tentative's direction; the state line may differ by π.
    const Vec2 old_u = lineDirection(t.y.x()), new_u = lineDirection(init.y.x());
    if (old_u.dot(new_u) < 0.0) {
      std::swap(info.t_min, info.t_max);
      info.t_min = -info.t_min;
      info.t_max = -info.t_max;
    }
    info.side = observeLine(pose, init.y.head<2>()).s;
  }
  state_.addFeature(info.id, obs.kind, init.y, init.G_x, init.G_z, obs.R);
  info_.push_back(info);
  ++stats_.promoted;
}

void FeatureSlam::expireTentatives(int64_t utime) {
  const int64_t timeout = micros(params_.tentative_timeout_s);
  const auto stale = [&](const Tentative& t) { return utime - t.info.last_utime > timeout; };
  stats_.tentative_expired += std::count_if(tentatives_.begin(), tentatives_.end(), stale);
  tentatives_.erase(std::remove_if(tentatives_.begin(), tentatives_.end(), stale), tentatives_.end());
}

std::vector<PoseStamped> FeatureSlam::takePoses() {
  std::vector<PoseStamped> out;
  out.swap(poses_);
  return out;
}

std::vector<std::pair<int64_t, int64_t>> FeatureSlam::takeMatches() {
  std::vector<std::pair<int64_t, int64_t>> out;
  out.swap(matches_);
  return out;
}

std::vector<ScanAnchors> FeatureSlam::takeAnchors() {
  std::vector<ScanAnchors> out;
  out.swap(anchors_);
  return out;
}

PoseStamped FeatureSlam::currentPose() const {
  PoseStamped p{filter_time_, state_.pose(), state_.poseCovariance()};
  if (!last_reading_ || odometry_queue_.empty()) return p;
  const OdometryMotionResult ahead = odometryMotion(*last_reading_, odometry_queue_.back(), params_.odometry);
  if (!ahead.ok()) return p;
  applyMotion(p.pose, p.cov, *ahead.motion);
  p.utime = odometry_queue_.back().utime;
  return p;
}

void FeatureSlam::emitAnchors(int64_t utime) { anchors_.push_back(anchorsNow(utime)); }

ScanAnchors FeatureSlam::anchorsNow(int64_t utime) const {
  ScanAnchors out;
  out.utime = utime;
  out.pose = {utime, state_.pose(), state_.poseCovariance()};
  const Pose2 pose = state_.pose();
  std::vector<std::pair<double, int>> near;
  const auto& features = state_.features();
  for (size_t j = 0; j < features.size(); ++j) {
    const Vec3 y = state_.featureMean(static_cast<int>(j));
    double distance = 0.0;
    if (features[j].kind == MapFeatureKind::Line) {
      const Vec2 u = lineDirection(y.x());
      const Vec2 foot = y.y() * Vec2(std::cos(y.x()), std::sin(y.x()));
      const double t = std::clamp(pose.translation().dot(u), info_[j].t_min, info_[j].t_max);
      distance = (foot + t * u - pose.translation()).norm();
    } else {
      distance = (y.head<2>() - pose.translation()).norm();
    }
    if (distance <= params_.anchor_radius) near.emplace_back(distance, static_cast<int>(j));
  }
  std::sort(near.begin(), near.end());
  if (near.size() > static_cast<size_t>(params_.max_anchors)) near.resize(static_cast<size_t>(params_.max_anchors));
  for (const auto& [distance, j] : near) {
    const MapFeatureKind kind = features[static_cast<size_t>(j)].kind;
    Observation probe;
    probe.kind = kind;
    probe.dim = parameterCount(kind);
    const auto lin = linearize(j, probe, nullptr);
    if (!lin) continue;
    AnchorObservation a;
    a.feature_id = info_[static_cast<size_t>(j)].id;
    a.kind = kind;
    a.z = probe.z - lin->innovation;  // innovation = 0 − h, so this is h(x̂, ŷ)
    if (kind != MapFeatureKind::Point) a.z.x() = wrapAngle(a.z.x());
    if (kind == MapFeatureKind::Corner) a.z.z() = wrapAngle(a.z.z());
    a.cov = state_.innovationCovariance(*lin);
    out.anchors.push_back(a);
  }
  return out;
}

FeatureMap FeatureSlam::map() const {
  FeatureMap m;
  m.utime = filter_time_ == std::numeric_limits<int64_t>::min() ? 0 : filter_time_;
  m.robot = {m.utime, state_.pose(), state_.poseCovariance()};
  const auto& features = state_.features();
  for (size_t j = 0; j < features.size(); ++j) {
    const FeatureInfo& info = info_[j];
    MapFeature f;
    f.id = info.id;
    f.kind = info.kind;
    f.params = state_.featureMean(static_cast<int>(j));
    f.cov = state_.featureCovariance(static_cast<int>(j));
    f.observations = info.observations;
    if (info.kind == MapFeatureKind::Line) {
      const double alpha = f.params.x(), d = f.params.y();
      const Vec2 u = lineDirection(alpha), foot = d * Vec2(std::cos(alpha), std::sin(alpha));
      f.endpoint_a = foot + info.t_min * u;
      f.endpoint_b = foot + info.t_max * u;
      if (d < 0.0) {  // report d ≥ 0 (2.9): the same line with α + π
        f.params.x() = wrapAngle(alpha + std::numbers::pi);
        f.params.y() = -d;
        f.cov(0, 1) = f.cov(1, 0) = -f.cov(0, 1);
      }
    }
    m.features.push_back(f);
  }
  return m;
}

}  // namespace polarslam
