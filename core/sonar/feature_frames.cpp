#include "sonar/feature_frames.hpp"

#include <cmath>
#include <numbers>

namespace polarslam {
namespace {

/// ∂(T ⊕ p)/∂T for a point p given in T's frame.
Eigen::Matrix<double, 2, 3> pointPoseJacobian(const Pose2& T, const Vec2& p) {
  const double c = std::cos(T.theta), s = std::sin(T.theta);
  Eigen::Matrix<double, 2, 3> J;
  J << 1.0, 0.0, -s * p.x() - c * p.y(),
       0.0, 1.0, c * p.x() - s * p.y();
  return J;
}

Mat2 rotation(double angle) {
  Mat2 R;
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return R;
}

}  // namespace

LineFeature transformLine(const LineFeature& line, const Pose2& T, const Mat3& T_cov) {
  LineFeature out = line;
  const double alpha_prime = wrapAngle(T.theta + line.alpha);
  const double d_prime = line.d + T.x * std::cos(alpha_prime) + T.y * std::sin(alpha_prime);
  const double s = d_prime >= 0.0 ? 1.0 : -1.0;
  out.alpha = s > 0.0 ? alpha_prime : wrapAngle(alpha_prime + std::numbers::pi);
  out.d = std::abs(d_prime);
  // Notes §17.8: at the stored (flipped) α the trigonometric entries carry no s.
  const double c = std::cos(out.alpha), sn = std::sin(out.alpha);
  const double lever = -T.x * sn + T.y * c;
  Mat2 Gz;
  Gz << 1.0, 0.0, lever, s;
  Eigen::Matrix<double, 2, 3> Gx;
  Gx << 0.0, 0.0, 1.0, c, sn, lever;
  out.cov = Gz * line.cov * Gz.transpose() + Gx * T_cov * Gx.transpose();
  out.random_cov = Gz * line.random_cov * Gz.transpose();
  out.systematic_bound = {line.systematic_bound.x(),
                          std::abs(lever) * line.systematic_bound.x() + line.systematic_bound.y()};
  out.endpoint_a = T.transform(line.endpoint_a);
  out.endpoint_b = T.transform(line.endpoint_b);
  return out;
}

CornerFeature transformCorner(const CornerFeature& corner, const Pose2& T, const Mat3& T_cov) {
  CornerFeature out = corner;
  const Vec2 apex = T.transform({corner.x, corner.y});
  out.x = apex.x();
  out.y = apex.y();
  out.gamma = wrapAngle(corner.gamma + T.theta);
  Mat3 Jz = Mat3::Identity();
  Jz.topLeftCorner<2, 2>() = rotation(T.theta);
  Mat3 JT = Mat3::Zero();
  JT.topRows<2>() = pointPoseJacobian(T, {corner.x, corner.y});
  JT(2, 2) = 1.0;
  out.cov = Jz * corner.cov * Jz.transpose() + JT * T_cov * JT.transpose();
  return out;
}

PointFeature transformPoint(const PointFeature& point, const Pose2& T, const Mat3& T_cov) {
  PointFeature out = point;
  const Vec2 p = T.transform({point.x, point.y});
  out.x = p.x();
  out.y = p.y();
  const Mat2 R = rotation(T.theta);
  const auto JT = pointPoseJacobian(T, {point.x, point.y});
  out.cov = R * point.cov * R.transpose() + JT * T_cov * JT.transpose();
  return out;
}

FeatureSet transformFeatures(const FeatureSet& set, const Pose2& T, const Mat3& T_cov) {
  FeatureSet out = set;
  for (auto& l : out.lines) l = transformLine(l, T, T_cov);
  for (auto& c : out.corners) c = transformCorner(c, T, T_cov);
  for (auto& p : out.points) p = transformPoint(p, T, T_cov);
  return out;
}

FeatureSet toBaseFrame(const FeatureSet& set) {
  if (set.frame == "base") return set;
  FeatureSet out = transformFeatures(set, set.sensor_pose);
  out.frame = "base";
  out.sensor_pose = Pose2();
  return out;
}

}  // namespace polarslam
