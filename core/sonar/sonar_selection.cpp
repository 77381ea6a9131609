#include "sonar/sonar_selection.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "sonar/feature_frames.hpp"

namespace polarslam {
namespace {

struct Reading {
  int index = 0;
  Vec2 point = Vec2::Zero();  ///< laser frame
  double range = 0.0;
};

double largestEigenvalue(const Mat2& cov) {
  const Eigen::SelfAdjointEigenSolver<Mat2> eig(0.5 * (cov + cov.transpose()));
  return std::max(0.0, eig.eigenvalues().maxCoeff());
}

bool validBeam(const LaserScan& scan, int i) {
  return i >= 0 && i < static_cast<int>(scan.size()) && scan.valid(static_cast<size_t>(i));
}

/// Consecutive valid readings walking from `start` by `step`, stopping at a gap, a range jump or
/// `max_extent` from `centre`.
std::vector<Reading> sideReadings(const LaserScan& scan, int start, int step, const Vec2& centre,
                                  const SonarSelectionParams& p) {
  std::vector<Reading> side;
  const int limit = p.step_side_beams + static_cast<int>(std::ceil(p.bump_radius / (scan.angle_increment * 0.3)));
  for (int i = start, n = 0; n < limit && validBeam(scan, i); i += step, ++n) {
    const Reading r{i, scan.point(static_cast<size_t>(i)), scan.ranges[static_cast<size_t>(i)]};
    if ((r.point - centre).norm() > p.step_max_extent) break;
    if (!side.empty() && std::abs(r.range - side.back().range) > p.jump) break;
    side.push_back(r);
  }
  return side;
}

Vec2 centroid(const std::vector<Reading>& side) {
  Vec2 c = Vec2::Zero();
  for (const auto& r : side) c += r.point;
  return c / static_cast<double>(side.size());
}

Mat2 scatter(const std::vector<Reading>& side, const Vec2& c) {
  Mat2 S = Mat2::Zero();
  for (const auto& r : side) S += (r.point - c) * (r.point - c).transpose();
  return S;
}

/// Unit normal of the best-fitting line through scatter S (eigenvector of the smallest eigenvalue).
Vec2 normalOf(const Mat2& S) {
  const Eigen::SelfAdjointEigenSolver<Mat2> eig(S);
  return eig.eigenvectors().col(0).normalized();
}

/// Readings of `side` farther than `radius` from q (the surface around the sonar point).
std::vector<Reading> beyond(const std::vector<Reading>& side, const Vec2& q, double radius) {
  std::vector<Reading> out;
  for (const Reading& r : side)
    if ((r.point - q).norm() > radius) out.push_back(r);
  return out;
}

/// Bend or step between the surfaces on either side of the sonar point (a corner, a doorway, a
/// recess): the two sides fitted with a shared normal differ in offset, or their normals differ.
bool bendOrStep(const std::vector<Reading>& left, const std::vector<Reading>& right, const SonarSelectionParams& p) {
  const Vec2 cl = centroid(left), cr = centroid(right);
  const Mat2 Sl = scatter(left, cl), Sr = scatter(right, cr);
  if (std::acos(std::min(1.0, std::abs(normalOf(Sl).dot(normalOf(Sr))))) > p.bend_angle) return true;
  const Mat2 pooled = Sl + Sr;
  const Vec2 n = normalOf(pooled), along(-n.y(), n.x());
  const double step = std::abs((cl - cr).dot(n));
  const double spread = along.dot(pooled * along), lever = (cl - cr).dot(along);
  const double sigma2 = p.laser_range_sigma * p.laser_range_sigma;
  const double var = sigma2 * (1.0 / static_cast<double>(left.size()) + 1.0 / static_cast<double>(right.size())) +
                     (spread > 0.0 ? lever * lever * sigma2 / spread : 0.0);
  return step > std::max(p.step_sigmas * std::sqrt(var), p.min_step);
}

/// A bump (door jamb, moulding) at the sonar point: a short run of readings next to it stands off
/// the surface fitted to the readings around it. Runs of 1–`bump_max_readings` readings within
/// `bump_radius` of the point are tested; the threshold allows for the number of runs tried.
bool bump(const std::vector<Reading>& near_left, const std::vector<Reading>& near_right,
          const std::vector<Reading>& reference, const SonarSelectionParams& p) {
  const Vec2 c = centroid(reference);
  const Vec2 n = normalOf(scatter(reference, c));
  const double sigma = p.laser_range_sigma;
  const double reference_var = 4.0 / static_cast<double>(reference.size());  // end-of-line prediction
  for (const auto* side : {&near_left, &near_right}) {
    for (size_t first = 0; first < side->size(); ++first) {
      double sum = 0.0;
      for (size_t k = first; k < side->size() && k < first + static_cast<size_t>(p.bump_max_readings); ++k) {
        sum += ((*side)[k].point - c).dot(n);
        const double count = static_cast<double>(k - first + 1);
        const double mean = sum / count;
        const double sd = sigma * std::sqrt(1.0 / count + reference_var);
        if (std::abs(mean) > std::max(p.bump_sigmas * sd, p.min_step)) return true;
      }
    }
  }
  return false;
}

/// The laser's own evidence of a discontinuity at the sonar point q (laser frame), around beam
/// `centre`: bend, step or bump.
bool laserBreak(const LaserScan& scan, int centre, const Vec2& q, const SonarSelectionParams& p) {
  const size_t need = static_cast<size_t>(std::max(2, p.step_min_beams));
  std::vector<Reading> left = sideReadings(scan, centre, -1, q, p), right = sideReadings(scan, centre + 1, +1, q, p);
  const std::vector<Reading> far_left = beyond(left, q, p.bump_radius), far_right = beyond(right, q, p.bump_radius);
  if (far_left.size() >= need && far_right.size() >= need && bendOrStep(far_left, far_right, p)) return true;
  std::vector<Reading> reference = far_left;
  reference.insert(reference.end(), far_right.begin(), far_right.end());
  if (reference.size() < 2 * need) return false;
  std::vector<Reading> near_left, near_right;
  for (const Reading& r : left)
    if ((r.point - q).norm() <= p.bump_radius) near_left.push_back(r);
  for (const Reading& r : right)
    if ((r.point - q).norm() <= p.bump_radius) near_right.push_back(r);
  return bump(near_left, near_right, reference, p);
}

bool nearSegmentEnd(const Vec2& point, const std::vector<Vec2>& ends, double gate) {
  for (const Vec2& e : ends)
    if ((e - point).norm() <= gate) return true;
  return false;
}

bool onSonarPlane(const Vec2& point, const std::vector<LineFeature>& planes, double gate) {
  for (const LineFeature& l : planes)
    if (std::abs(point.x() * std::cos(l.alpha) + point.y() * std::sin(l.alpha) - l.d) <= gate) return true;
  return false;
}

/// A break among the readings around beam `centre_index` (a "no return" next to a return, or a jump).
bool rawBreak(const LaserScan& scan, int first, int last, double jump) {
  for (int i = first; i < last; ++i) {
    const bool a = validBeam(scan, i), b = validBeam(scan, i + 1);
    if (a != b) return true;
    if (a && b && std::abs(scan.ranges[static_cast<size_t>(i)] - scan.ranges[static_cast<size_t>(i + 1)]) > jump)
      return true;
  }
  return false;
}

}  // namespace

const char* toString(SonarVerdict verdict) {
  switch (verdict) {
    case SonarVerdict::LaserBreak: return "laser break";
    case SonarVerdict::LaserSegmentEnd: return "laser segment end";
    case SonarVerdict::LaserSurface: return "laser surface without break";
    case SonarVerdict::NoLaserReturn: return "no laser return";
    case SonarVerdict::OutsideLaserView: return "outside laser view";
    case SonarVerdict::Glass: return "glass";
    case SonarVerdict::FreeSpace: return "laser free space";
    case SonarVerdict::BehindLaserSurface: return "behind laser surface";
  }
  return "?";
}

SonarVerdict judgeSonarPoint(const Vec2& point, const Mat2& cov, const LaserEvidence& evidence,
                             const SonarSelectionParams& p) {
  if (!evidence.scan || evidence.scan->size() < 2) return SonarVerdict::OutsideLaserView;
  const LaserScan& scan = *evidence.scan;
  const Vec2 q = scan.laser_pose.inverseTransform(point);
  const double rho = q.norm(), beta = std::atan2(q.y(), q.x());
  const double f = (beta - scan.angle_min) / scan.angle_increment;
  const int n = static_cast<int>(scan.size());
  if (!(rho > 1e-3) || f < -0.5 || f > n - 0.5) return SonarVerdict::OutsideLaserView;
  const double gate =
      p.gate_sigmas * std::sqrt(p.laser_range_sigma * p.laser_range_sigma + largestEigenvalue(cov)) + p.gate_margin;
  const int centre = static_cast<int>(std::lround(f));
  const int half = static_cast<int>(std::ceil(std::atan2(gate, rho) / scan.angle_increment)) + 1;
  const int first = std::max(0, centre - half), last = std::min(n - 1, centre + half);

  bool any = false, near = false, all_beyond = true, all_in_front = true;
  for (int i = first; i <= last; ++i) {
    if (!validBeam(scan, i)) continue;
    any = true;
    const double r = scan.ranges[static_cast<size_t>(i)];
    near |= (scan.point(static_cast<size_t>(i)) - q).norm() <= gate;
    all_beyond &= r > rho;
    all_in_front &= r < rho;
  }
  if (!any) return SonarVerdict::NoLaserReturn;
  if (!near) {
    if (all_beyond) return onSonarPlane(point, evidence.sonar_planes, gate) ? SonarVerdict::Glass : SonarVerdict::FreeSpace;
    if (all_in_front) return SonarVerdict::BehindLaserSurface;
    return SonarVerdict::LaserBreak;  // the returns straddle the point: an edge between two surfaces
  }
  if (nearSegmentEnd(point, evidence.segment_ends, gate + p.segment_end_gate)) return SonarVerdict::LaserSegmentEnd;
  if (rawBreak(scan, first, last, p.jump)) return SonarVerdict::LaserBreak;
  return laserBreak(scan, centre, q, p) ? SonarVerdict::LaserBreak : SonarVerdict::LaserSurface;
}

LaserEvidence makeLaserEvidence(const LaserScan* normalized_scan, const FeatureSet& laser_features,
                                const FeatureSet& sonar_base, const std::vector<double>& hint_bearings,
                                double hint_tolerance) {
  LaserEvidence e;
  e.scan = normalized_scan;
  const Pose2 laser_pose = laser_features.frame == "base" ? Pose2() : laser_features.sensor_pose;
  const FeatureSet laser_base = toBaseFrame(laser_features);
  auto add = [&](const Vec2& end) {
    const Vec2 q = laser_pose.inverseTransform(end);
    const double bearing = std::atan2(q.y(), q.x());
    for (double h : hint_bearings)
      if (std::abs(wrapAngle(bearing - h)) <= hint_tolerance) return;
    e.segment_ends.push_back(end);
  };
  for (const LineFeature& l : laser_base.lines) {
    add(l.endpoint_a);
    add(l.endpoint_b);
  }
  for (const CornerFeature& c : laser_base.corners) add({c.x, c.y});
  e.sonar_planes = sonar_base.lines;
  return e;
}

FeatureSet selectSonarFeatures(const FeatureSet& sonar, const LaserEvidence& evidence,
                               const SonarSelectionParams& p, SelectionCounts* counts) {
  SelectionCounts local;
  SelectionCounts& n = counts ? *counts : local;
  FeatureSet out = sonar;
  out.lines.clear();
  out.corners.clear();
  out.points.clear();
  auto tally = [&](SonarVerdict v, bool is_point) {
    switch (v) {
      case SonarVerdict::FreeSpace:
      case SonarVerdict::BehindLaserSurface: ++n.spurious; ++out.num_rejected; return false;
      case SonarVerdict::LaserSurface:
        if (is_point) {
          ++n.unsupported;
          ++out.num_rejected;
          return false;
        }
        ++n.kept_supported;
        return true;
      case SonarVerdict::NoLaserReturn:
      case SonarVerdict::OutsideLaserView: ++n.kept_unverified; return true;
      case SonarVerdict::Glass: ++n.kept_glass; return true;
      default: ++n.kept_supported; return true;
    }
  };
  for (const LineFeature& l : sonar.lines) {
    // The plane's reflection point is the normal foot, stored as the (degenerate) segment.
    Mat2 foot_cov = Mat2::Identity() * (l.cov(1, 1) + l.d * l.d * l.cov(0, 0));
    if (tally(judgeSonarPoint(l.endpoint_a, foot_cov, evidence, p), false)) out.lines.push_back(l);
  }
  for (const CornerFeature& c : sonar.corners)
    if (tally(judgeSonarPoint({c.x, c.y}, c.cov.topLeftCorner<2, 2>(), evidence, p), false)) out.corners.push_back(c);
  for (const PointFeature& pt : sonar.points)
    if (tally(judgeSonarPoint({pt.x, pt.y}, pt.cov, evidence, p), true)) out.points.push_back(pt);
  return out;
}

std::vector<BreakHint> sonarBreakHints(const FeatureSet& sonar_base, const Pose2& laser_pose) {
  std::vector<BreakHint> hints;
  auto add = [&](const Vec2& p, const Mat2& cov, bool corner) {
    const Vec2 q = laser_pose.inverseTransform(p);
    const double r = q.norm();
    if (!(r > 1e-3)) return;
    const Vec2 across = Vec2(-q.y(), q.x()) / r;
    Mat2 R;  // base → laser rotation
    R << std::cos(laser_pose.theta), std::sin(laser_pose.theta), -std::sin(laser_pose.theta), std::cos(laser_pose.theta);
    const double var_across = across.dot(R * cov * R.transpose() * across);
    hints.push_back({std::atan2(q.y(), q.x()), r, std::sqrt(std::max(0.0, var_across)) / r, corner});
  };
  for (const CornerFeature& c : sonar_base.corners) add({c.x, c.y}, c.cov.topLeftCorner<2, 2>(), true);
  for (const PointFeature& p : sonar_base.points) add({p.x, p.y}, p.cov, false);
  std::sort(hints.begin(), hints.end(), [](const BreakHint& a, const BreakHint& b) { return a.bearing < b.bearing; });
  return hints;
}

}  // namespace polarslam
