#include "sonar/sonar_features.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "sonar/feature_frames.hpp"

namespace polarslam {
namespace {

/// ∂(x, y)/∂(ρ, ψ) of the point ρ·(cos ψ, sin ψ).
Mat2 polarJacobian(double range, double bearing) {
  const double c = std::cos(bearing), s = std::sin(bearing);
  Mat2 J;
  J << c, -range * s, s, range * c;
  return J;
}

bool finiteMatrix(const Mat2& m) { return m.allFinite(); }

}  // namespace

bool sonarTargetCovariance(const SonarTarget& target, const SonarFeatureParams& params, Mat2& cov) {
  if (!finiteMatrix(target.cov) || target.cov(0, 0) < 0.0 || target.cov(1, 1) < 0.0 ||
      std::abs(target.cov(0, 1) - target.cov(1, 0)) > 1e-9 * (1.0 + std::abs(target.cov(0, 1))))
    return false;
  cov = target.cov;
  cov(0, 0) = std::max(cov(0, 0), params.range_sigma_floor * params.range_sigma_floor);
  cov(1, 1) = std::max(cov(1, 1), params.bearing_sigma_floor * params.bearing_sigma_floor);
  return cov.determinant() > 0.0;
}

LineFeature sonarPlaneLine(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                           const Mat3& mount_cov) {
  LineFeature in_array;
  in_array.source = FeatureSource::Sonar;
  in_array.alpha = wrapAngle(target.bearing);
  in_array.d = target.range;
  // (α, d) = (ψ, ρ): swap the (range, bearing) covariance into (α, d) order.
  in_array.cov << range_bearing_cov(1, 1), range_bearing_cov(1, 0), range_bearing_cov(0, 1), range_bearing_cov(0, 0);
  in_array.random_cov = in_array.cov;
  const Vec2 foot = target.range * Vec2(std::cos(target.bearing), std::sin(target.bearing));
  in_array.endpoint_a = in_array.endpoint_b = foot;
  LineFeature out = transformLine(in_array, mount, mount_cov);
  out.random_cov = out.cov;
  out.num_points = 0;
  return out;
}

PointFeature sonarEdgePoint(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                            const Mat3& mount_cov) {
  PointFeature in_array;
  in_array.source = FeatureSource::Sonar;
  in_array.x = target.range * std::cos(target.bearing);
  in_array.y = target.range * std::sin(target.bearing);
  const Mat2 J = polarJacobian(target.range, target.bearing);
  in_array.cov = J * range_bearing_cov * J.transpose();
  return transformPoint(in_array, mount, mount_cov);
}

CornerFeature sonarCornerFeature(const SonarTarget& target, const Pose2& mount, const Mat2& range_bearing_cov,
                                 const Mat3& mount_cov) {
  CornerFeature in_array;
  in_array.source = FeatureSource::Sonar;
  in_array.convex = false;  // the array classifies concave right angles as corners
  in_array.x = target.range * std::cos(target.bearing);
  in_array.y = target.range * std::sin(target.bearing);
  in_array.gamma = wrapAngle(target.bearing + std::numbers::pi);  // apex → array
  const Mat2 J = polarJacobian(target.range, target.bearing);
  in_array.cov.setZero();
  in_array.cov.topLeftCorner<2, 2>() = J * range_bearing_cov * J.transpose();
  in_array.cov(2, 2) = kUnknownAngleVariance;
  return transformCorner(in_array, mount, mount_cov);
}

FeatureSet sonarFeatures(const SonarScan& scan, const SonarFeatureParams& params, SonarFeatureCounts* counts) {
  FeatureSet set;
  set.utime = scan.utime;
  set.seq = scan.seq;
  set.frame = "base";
  SonarFeatureCounts local;
  SonarFeatureCounts& n = counts ? *counts : local;
  const bool mount_ok = std::isfinite(scan.sensor_pose.x) && std::isfinite(scan.sensor_pose.y) &&
                        std::isfinite(scan.sensor_pose.theta) && params.mount_cov.allFinite();
  for (const SonarTarget& t : scan.targets) {
    Mat2 cov;
    const bool usable = mount_ok && std::isfinite(t.range) && std::isfinite(t.bearing) && t.range >= params.min_range &&
                        (!(scan.range_max > 0.0) || t.range <= scan.range_max) &&
                        sonarTargetCovariance(t, params, cov);
    if (t.kind == SonarKind::Unknown) {
      ++n.unknown;
      ++set.num_rejected;
      continue;
    }
    if (!usable) {
      ++n.invalid;
      ++set.num_rejected;
      continue;
    }
    switch (t.kind) {
      case SonarKind::Plane: set.lines.push_back(sonarPlaneLine(t, scan.sensor_pose, cov, params.mount_cov)); break;
      case SonarKind::Corner: set.corners.push_back(sonarCornerFeature(t, scan.sensor_pose, cov, params.mount_cov)); break;
      case SonarKind::Edge: set.points.push_back(sonarEdgePoint(t, scan.sensor_pose, cov, params.mount_cov)); break;
      default:
        ++n.invalid;
        ++set.num_rejected;
    }
  }
  return set;
}

}  // namespace polarslam
