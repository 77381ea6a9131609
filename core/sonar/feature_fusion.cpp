#include "sonar/feature_fusion.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/chi_squared.hpp"
#include "sonar/feature_frames.hpp"

namespace polarslam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double quadraticForm(const Eigen::VectorXd& nu, const Eigen::MatrixXd& S) {
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return kInfinity;
  return nu.dot(llt.solve(nu));
}

/// Information matrix of a corner: with an unknown γ only the apex block counts.
Mat3 cornerInformation(const CornerFeature& c) {
  Mat3 info = Mat3::Zero();
  if (cornerOrientationUnknown(c.cov)) {
    info.topLeftCorner<2, 2>() = c.cov.topLeftCorner<2, 2>().inverse();
  } else {
    info = c.cov.inverse();
  }
  return info;
}

double gate(int dof, double probability) { return chiSquaredQuantile(probability, dof); }

int64_t seconds(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

}  // namespace

double lineDistance2(const LineFeature& a, const LineFeature& b) {
  const Eigen::Vector2d nu(wrapAngle(b.alpha - a.alpha), b.d - a.d);
  return quadraticForm(nu, a.cov + b.cov);
}

LineFeature fuseLines(const LineFeature& a, const LineFeature& b) {
  const Mat2 info_b = b.cov.inverse();
  const Mat2 P = (a.cov.inverse() + info_b).inverse();
  const Vec2 nu(wrapAngle(b.alpha - a.alpha), b.d - a.d);
  const Vec2 z = Vec2(a.alpha, a.d) + P * info_b * nu;
  LineFeature out = a;
  out.source = FeatureSource::Fused;
  out.alpha = wrapAngle(z.x());
  out.d = z.y();
  out.cov = 0.5 * (P + P.transpose());
  out.random_cov = out.cov;
  out.systematic_bound = a.systematic_bound.cwiseMin(b.systematic_bound);
  return out;
}

double cornerDistance2(const CornerFeature& a, const CornerFeature& b, int* dof) {
  const bool both_oriented = !cornerOrientationUnknown(a.cov) && !cornerOrientationUnknown(b.cov);
  const int n = both_oriented ? 3 : 2;
  if (dof) *dof = n;
  const Vec3 nu(b.x - a.x, b.y - a.y, wrapAngle(b.gamma - a.gamma));
  const Mat3 S = a.cov + b.cov;
  return quadraticForm(nu.head(n), S.topLeftCorner(n, n));
}

CornerFeature fuseCorners(const CornerFeature& a, const CornerFeature& b) {
  const Mat3 info_a = cornerInformation(a), info_b = cornerInformation(b);
  Mat3 info = info_a + info_b;
  CornerFeature out = a;
  out.source = FeatureSource::Fused;
  out.num_points = a.num_points + b.num_points;
  const Vec3 nu(b.x - a.x, b.y - a.y, wrapAngle(b.gamma - a.gamma));
  Mat3 P = Mat3::Zero();
  const bool gamma_known = info(2, 2) > 0.0;
  if (gamma_known) {
    P = info.inverse();
  } else {
    P.topLeftCorner<2, 2>() = info.topLeftCorner<2, 2>().inverse();
    P(2, 2) = kUnknownAngleVariance;
  }
  const Vec3 z = Vec3(a.x, a.y, a.gamma) + P * info_b * nu;
  out.x = z.x();
  out.y = z.y();
  // z = P(I_a·z_a + I_b·z_b): an unknown γ has no information, so its placeholder value drops out.
  out.gamma = gamma_known ? wrapAngle(z.z()) : a.gamma;
  out.cov = 0.5 * (P + P.transpose());
  return out;
}

bool footOnSegment(const LineFeature& sonar_plane, const LineFeature& laser_line, double tolerance) {
  const Vec2 e = laser_line.endpoint_b - laser_line.endpoint_a;
  const double length2 = e.squaredNorm();
  if (length2 <= 0.0) return (sonar_plane.endpoint_a - laser_line.endpoint_a).norm() <= tolerance;
  const double t = (sonar_plane.endpoint_a - laser_line.endpoint_a).dot(e) / length2;
  const double length = std::sqrt(length2);
  return t * length >= -tolerance && (t - 1.0) * length <= tolerance;
}

FeatureSet fuseFeatureSets(const FeatureSet& laser_base, const FeatureSet& sonar_base, const FusionMathParams& params,
                           FusionCounts* counts) {
  FusionCounts local;
  FusionCounts& n = counts ? *counts : local;
  FeatureSet out = laser_base;
  out.num_rejected += sonar_base.num_rejected;
  const double line_gate = gate(2, params.gate_probability);
  for (const LineFeature& s : sonar_base.lines) {
    int match = -1, matches = 0;
    double best = kInfinity;
    for (size_t i = 0; i < out.lines.size(); ++i) {
      const LineFeature& l = out.lines[i];
      if (l.source == FeatureSource::Sonar) continue;  // two sonar planes: left to the filter
      const double d2 = lineDistance2(l, s);
      if (d2 > line_gate || !footOnSegment(s, l, params.foot_tolerance)) continue;
      ++matches;
      if (d2 < best) {
        best = d2;
        match = static_cast<int>(i);
      }
    }
    if (matches == 1) {
      out.lines[static_cast<size_t>(match)] = fuseLines(out.lines[static_cast<size_t>(match)], s);
      ++n.fused_lines;
    } else {
      n.ambiguous += matches > 1;
      out.lines.push_back(s);
      ++n.sonar_lines_alone;
    }
  }
  for (const CornerFeature& s : sonar_base.corners) {
    int match = -1, matches = 0;
    double best = kInfinity;
    for (size_t i = 0; i < out.corners.size(); ++i) {
      const CornerFeature& c = out.corners[i];
      if (c.source == FeatureSource::Sonar || c.convex != s.convex) continue;
      int dof = 2;
      const double d2 = cornerDistance2(c, s, &dof);
      if (d2 > gate(dof, params.gate_probability)) continue;
      ++matches;
      if (d2 < best) {
        best = d2;
        match = static_cast<int>(i);
      }
    }
    if (matches == 1) {
      out.corners[static_cast<size_t>(match)] = fuseCorners(out.corners[static_cast<size_t>(match)], s);
      ++n.fused_corners;
    } else {
      n.ambiguous += matches > 1;
      out.corners.push_back(s);
      ++n.sonar_corners_alone;
    }
  }
  for (const PointFeature& p : sonar_base.points) {
    out.points.push_back(p);
    ++n.sonar_points;
  }
  return out;
}

// ---- FeatureFusion ---------------------------------------------------------------------------------

FeatureFusion::FeatureFusion(FeatureFusionParams params) : params_(params), odometry_(5.0, params.odometry) {}

void FeatureFusion::observeTime(int64_t utime) { stream_time_ = std::max(stream_time_, utime); }

bool FeatureFusion::addOdometry(const OdometryReading& reading) {
  if (!odometry_.add(reading)) return false;
  observeTime(reading.utime);
  process(false);
  return true;
}

bool FeatureFusion::addLaserScan(const LaserScan& scan) {
  if (!validateScan(scan).empty()) return false;
  raw_scans_.push_back(normalizedScan(scan));
  observeTime(scan.utime);
  // Kept as long as a late laser set may still ask for its raw scan.
  const int64_t keep_from = stream_time_ - seconds(params_.max_laser_lag_s + params_.laser_wait_s);
  while (raw_scans_.size() > 20 && raw_scans_.front().utime < keep_from) raw_scans_.pop_front();
  if (params_.use_laser && params_.use_sonar && (laser_sets_due_.empty() || scan.utime > laser_sets_due_.back()))
    laser_sets_due_.push_back(scan.utime);
  process(false);
  return true;
}

bool FeatureFusion::addLaserFeatures(const FeatureSet& laser_features) {
  if (!params_.use_laser) return false;
  if (laser_features.utime < emitted_until_ ||
      (!pending_laser_.empty() && laser_features.utime < pending_laser_.back().utime)) {
    ++stats_.late;
    return false;
  }
  ++stats_.laser_sets;
  while (!laser_sets_due_.empty() && laser_sets_due_.front() <= laser_features.utime) laser_sets_due_.pop_front();
  pending_laser_.push_back(laser_features);
  observeTime(laser_features.utime);
  process(false);
  return true;
}

bool FeatureFusion::addSonar(const SonarScan& scan) {
  if (!params_.use_sonar) return false;
  if (scan.utime < emitted_until_) {
    ++stats_.late;
    return false;
  }
  ++stats_.sonar_scans;
  const auto at = std::upper_bound(pending_sonar_.begin(), pending_sonar_.end(), scan.utime,
                                   [](int64_t t, const SonarScan& s) { return t < s.utime; });
  pending_sonar_.insert(at, scan);
  observeTime(scan.utime);
  process(false);
  return true;
}

std::vector<FeatureSet> FeatureFusion::takeReady() {
  std::vector<FeatureSet> out;
  out.swap(ready_);
  return out;
}

void FeatureFusion::flush() { process(true); }

bool FeatureFusion::laserReady(const FeatureSet& laser) const {
  // Stream time alone decides, never which messages happen to have arrived: live, the laser
  // features come from another process and reach this stage after the sonar cycles of their own
  // time, offline before them, and both must fuse the same cycles.
  return !params_.use_sonar || stream_time_ - laser.utime >= seconds(params_.sonar_wait_s);
}

void FeatureFusion::dropStalledLaserSets() {
  while (!laser_sets_due_.empty() && stream_time_ - laser_sets_due_.front() > seconds(params_.max_laser_lag_s)) {
    laser_sets_due_.pop_front();
    ++stats_.missing_laser_sets;
  }
}

bool FeatureFusion::laserSetDue(int64_t until) const {
  return !laser_sets_due_.empty() && laser_sets_due_.front() <= until;
}

void FeatureFusion::process(bool flushing) {
  dropStalledLaserSets();
  const int64_t offset = seconds(params_.max_sonar_offset_s);
  while (true) {
    if (!pending_laser_.empty()) {
      const FeatureSet& laser = pending_laser_.front();
      // Sonar cycles too old for this (or any later) laser set go alone, first.
      if (!pending_sonar_.empty() && pending_sonar_.front().utime < laser.utime - offset) {
        emitSonarAlone(pending_sonar_.front());
        pending_sonar_.pop_front();
        continue;
      }
      if (!flushing && !laserReady(laser)) return;
      // Per array, the cycle closest in time within the offset.
      std::map<int, size_t> chosen;
      for (size_t i = 0; i < pending_sonar_.size(); ++i) {
        const SonarScan& s = pending_sonar_[i];
        if (std::llabs(s.utime - laser.utime) > offset) continue;
        const auto it = chosen.find(s.sensor_id);
        if (it == chosen.end() ||
            std::llabs(s.utime - laser.utime) < std::llabs(pending_sonar_[it->second].utime - laser.utime))
          chosen[s.sensor_id] = i;
      }
      std::vector<bool> is_chosen(pending_sonar_.size(), false);
      for (const auto& [id, i] : chosen) is_chosen[i] = true;
      std::vector<SonarScan> used;
      std::deque<SonarScan> keep;
      for (size_t i = 0; i < pending_sonar_.size(); ++i) {
        const SonarScan& s = pending_sonar_[i];
        if (is_chosen[i]) used.push_back(s);
        else if (s.utime <= laser.utime) emitSonarAlone(s);  // an array's second cycle near this scan
        else keep.push_back(s);
      }
      pending_sonar_.swap(keep);
      const FeatureSet set = laser;
      pending_laser_.pop_front();
      emitLaser(set, used);
      continue;
    }
    if (pending_sonar_.empty()) return;
    const SonarScan& s = pending_sonar_.front();
    // With the laser in use, a cycle waits a while for a laser set to fuse with, and for the set
    // of every raw scan near it already received, however late; without the laser, cycles of one
    // time stamp go out together once time has moved past it.
    const bool waited = params_.use_laser ? stream_time_ - s.utime >= seconds(params_.laser_wait_s) &&
                                                !laserSetDue(s.utime + offset)
                                          : stream_time_ > s.utime;
    if (!flushing && !waited) return;
    if (params_.use_laser) {
      emitSonarAlone(s);
      pending_sonar_.pop_front();
      continue;
    }
    const int64_t t = s.utime;
    std::vector<SonarScan> group;
    while (!pending_sonar_.empty() && pending_sonar_.front().utime == t) {
      group.push_back(pending_sonar_.front());
      pending_sonar_.pop_front();
    }
    FeatureSet set;
    set.utime = t;
    set.frame = "base";
    for (const SonarScan& g : group) {
      const FeatureSet f = sonarAt(g, t);
      set.lines.insert(set.lines.end(), f.lines.begin(), f.lines.end());
      set.corners.insert(set.corners.end(), f.corners.begin(), f.corners.end());
      set.points.insert(set.points.end(), f.points.begin(), f.points.end());
      set.num_rejected += f.num_rejected;
    }
    emit(std::move(set));
  }
}

void FeatureFusion::emitSonarAlone(const SonarScan& scan) {
  if (scan.utime < emitted_until_) {
    ++stats_.late;
    return;
  }
  FeatureSet set = sonarAt(scan, scan.utime);
  if (params_.laser_aided_selection) {
    if (const LaserScan* raw = rawScanAt(scan.utime)) {
      const LaserEvidence evidence = makeLaserEvidence(raw, FeatureSet{}, set);
      set = selectSonarFeatures(set, evidence, params_.selection, &stats_.selection);
    }
  }
  stats_.fusion.sonar_lines_alone += static_cast<int>(set.lines.size());
  stats_.fusion.sonar_corners_alone += static_cast<int>(set.corners.size());
  stats_.fusion.sonar_points += static_cast<int>(set.points.size());
  emit(std::move(set));
}

void FeatureFusion::emitLaser(const FeatureSet& laser, const std::vector<SonarScan>& sonar) {
  FeatureSet laser_base = toBaseFrame(laser);
  laser_base.frame = "base";
  laser_base.sensor_pose = Pose2();
  if (sonar.empty()) {
    emit(std::move(laser_base));
    return;
  }
  FeatureSet sonar_base;
  sonar_base.frame = "base";
  for (const SonarScan& s : sonar) {
    const FeatureSet f = sonarAt(s, laser.utime);
    sonar_base.lines.insert(sonar_base.lines.end(), f.lines.begin(), f.lines.end());
    sonar_base.corners.insert(sonar_base.corners.end(), f.corners.begin(), f.corners.end());
    sonar_base.points.insert(sonar_base.points.end(), f.points.begin(), f.points.end());
    sonar_base.num_rejected += f.num_rejected;
  }
  if (params_.laser_aided_selection) {
    const LaserScan* raw = rawScanAt(laser.utime);
    // Segment ends the segmenter made at a sonar hint are no laser support for that target.
    const LaserEvidence evidence = makeLaserEvidence(raw, laser, sonar_base, laser.break_hints);
    sonar_base = selectSonarFeatures(sonar_base, evidence, params_.selection, &stats_.selection);
  }
  emit(fuseFeatureSets(laser_base, sonar_base, params_.fusion, &stats_.fusion));
}

void FeatureFusion::emit(FeatureSet set) {
  set.frame = "base";
  set.sensor_pose = Pose2();
  set.seq = output_seq_++;
  emitted_until_ = std::max(emitted_until_, set.utime);
  ++stats_.output_sets;
  ready_.push_back(std::move(set));
}

FeatureSet FeatureFusion::sonarAt(const SonarScan& scan, int64_t utime) {
  FeatureSet set = sonarFeatures(scan, params_.sonar, &stats_.sonar);
  set.utime = utime;
  if (scan.utime == utime) return set;
  // The pose at the sonar cycle seen from the pose at `utime`.
  if (const auto motion = odometry_.motion(utime, scan.utime)) return transformFeatures(set, motion->delta, motion->cov);
  ++stats_.uncompensated;
  const double dt = std::abs(static_cast<double>(scan.utime - utime)) * 1e-6;
  const double step = params_.unknown_speed * dt, turn = params_.unknown_turn_rate * dt;
  return transformFeatures(set, Pose2(), Vec3(step * step, step * step, turn * turn).asDiagonal());
}

const LaserScan* FeatureFusion::rawScanAt(int64_t utime) const {
  for (const LaserScan& s : raw_scans_)
    if (s.utime == utime) return &s;
  return nullptr;
}

}  // namespace polarslam
