#include "grid/anchor_model.hpp"

#include <cmath>

namespace polarslam {
namespace {

AnchorPrediction predictLine(const Pose2& pose, const Vec3& y, double min_line_distance) {
  AnchorPrediction p;
  const double alpha_m = y.x(), d_m = y.y();
  const double c = std::cos(alpha_m), s = std::sin(alpha_m);
  double d_r = d_m - pose.x * c - pose.y * s;
  double alpha_r = wrapAngle(alpha_m - pose.theta);
  if (std::abs(d_r) < min_line_distance) return p;
  double sign = 1.0;
  if (d_r < 0.0) {
    d_r = -d_r;
    alpha_r = wrapAngle(alpha_r + std::numbers::pi);
    sign = -1.0;
  }
  p.valid = true;
  p.dims = 2;
  p.z = {alpha_r, d_r, 0.0};
  p.H_x(0, 2) = -1.0;
  p.H_x(1, 0) = -sign * c;
  p.H_x(1, 1) = -sign * s;
  p.H_y(0, 0) = 1.0;
  p.H_y(1, 0) = sign * (pose.x * s - pose.y * c);
  p.H_y(1, 1) = sign;
  return p;
}

AnchorPrediction predictPoint(const Pose2& pose, const Vec3& y) {
  AnchorPrediction p;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const double dx = y.x() - pose.x, dy = y.y() - pose.y;
  if (dx * dx + dy * dy < 1e-6) return p;
  const double x_r = c * dx + s * dy, y_r = -s * dx + c * dy;
  p.valid = true;
  p.dims = 2;
  p.z = {x_r, y_r, 0.0};
  p.H_x.topLeftCorner<2, 3>() << -c, -s, y_r,
                                  s, -c, -x_r;
  p.H_y.topLeftCorner<2, 2>() << c, s,
                                 -s, c;
  return p;
}

AnchorPrediction predictCorner(const Pose2& pose, const Vec3& y) {
  AnchorPrediction p;
  const double ex = pose.x - y.x(), ey = pose.y - y.y();  // robot minus apex
  const double t = ex * ex + ey * ey;
  if (t < 1e-6) return p;
  const double r = std::sqrt(t);
  p.valid = true;
  p.dims = 3;
  p.z = {wrapAngle(std::atan2(-ey, -ex) - pose.theta), r, wrapAngle(y.z() - pose.theta)};
  p.H_x << -ey / t, ex / t, -1.0,
            ex / r, ey / r, 0.0,
            0.0, 0.0, -1.0;
  p.H_y << ey / t, -ex / t, 0.0,
           -ex / r, -ey / r, 0.0,
           0.0, 0.0, 1.0;
  return p;
}

}  // namespace

AnchorPrediction predictAnchor(const Pose2& pose, const MapFeature& feature, double min_line_distance) {
  switch (feature.kind) {
    case MapFeatureKind::Line: return predictLine(pose, feature.params, min_line_distance);
    case MapFeatureKind::Point: return predictPoint(pose, feature.params);
    case MapFeatureKind::Corner: return predictCorner(pose, feature.params);
  }
  return {};
}

Vec3 anchorResidual(MapFeatureKind kind, const Vec3& measured, const Vec3& predicted) {
  Vec3 r = measured - predicted;
  switch (kind) {
    case MapFeatureKind::Line: r(0) = wrapAngle(r(0)); r(2) = 0.0; break;
    case MapFeatureKind::Point: r(2) = 0.0; break;
    case MapFeatureKind::Corner: r(0) = wrapAngle(r(0)); r(2) = wrapAngle(r(2)); break;
  }
  return r;
}

}  // namespace polarslam
