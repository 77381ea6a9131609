#pragma once
// SE(2) poses and angle helpers. Frames are right-handed, x forward, y left (REP-103).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace polarslam {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;

/// Wraps an angle into (-pi, pi].
inline double wrapAngle(double a) {
  if (!std::isfinite(a)) return a;
  a = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
  if (a <= 0.0) a += 2.0 * std::numbers::pi;
  return a - std::numbers::pi;
}

inline constexpr double deg2rad(double deg) { return deg * std::numbers::pi / 180.0; }
inline constexpr double rad2deg(double rad) { return rad * 180.0 / std::numbers::pi; }

struct Pose2 {
  double x = 0.0, y = 0.0, theta = 0.0;

  Pose2() = default;
  Pose2(double x_, double y_, double theta_) : x(x_), y(y_), theta(theta_) {}
  explicit Pose2(const Vec3& v) : x(v.x()), y(v.y()), theta(v.z()) {}

  Vec3 vec() const { return {x, y, theta}; }
  Vec2 translation() const { return {x, y}; }

  /// this ⊕ b: b expressed in this frame, returned in this frame's parent.
  Pose2 operator*(const Pose2& b) const {
    const double c = std::cos(theta), s = std::sin(theta);
    return {x + c * b.x - s * b.y, y + s * b.x + c * b.y, wrapAngle(theta + b.theta)};
  }
  /// ⊖this
  Pose2 inverse() const {
    const double c = std::cos(theta), s = std::sin(theta);
    return {-c * x - s * y, s * x - c * y, wrapAngle(-theta)};
  }
  /// Transforms a point from this frame into the parent frame.
  Vec2 transform(const Vec2& p) const {
    const double c = std::cos(theta), s = std::sin(theta);
    return {x + c * p.x() - s * p.y(), y + s * p.x() + c * p.y()};
  }
  /// Transforms a point from the parent frame into this frame.
  Vec2 inverseTransform(const Vec2& p) const {
    const double c = std::cos(theta), s = std::sin(theta);
    const double dx = p.x() - x, dy = p.y() - y;
    return {c * dx + s * dy, -s * dx + c * dy};
  }
};

inline bool finitePose(const Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.theta); }

/// Distance from p to the segment a–b; `s_out` receives where the closest point lies (0 at a, 1 at b).
inline double distanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b, double* s_out = nullptr) {
  const Vec2 e = b - a;
  const double s = e.squaredNorm() > 0.0 ? std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
  if (s_out) *s_out = s;
  return (a + s * e - p).norm();
}

/// Relative pose of b seen from a: (⊖a) ⊕ b.
inline Pose2 between(const Pose2& a, const Pose2& b) { return a.inverse() * b; }

/// Whether `b` lies within `translation` and `rotation` of `a`: between(a, b) without its sine and
/// cosine (a rotation keeps lengths; it is called in loops over every node of a map).
inline bool isNear(const Pose2& a, const Pose2& b, double translation, double rotation) {
  return std::hypot(b.x - a.x, b.y - a.y) <= translation && std::abs(wrapAngle(b.theta - a.theta)) <= rotation;
}

/// Jacobians of c = a ⊕ b with respect to a and b.
inline Mat3 composeJacobianA(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  Mat3 J = Mat3::Identity();
  J(0, 2) = -s * b.x - c * b.y;
  J(1, 2) = c * b.x - s * b.y;
  return J;
}
inline Mat3 composeJacobianB(const Pose2& a) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  Mat3 J = Mat3::Identity();
  J(0, 0) = c; J(0, 1) = -s;
  J(1, 0) = s; J(1, 1) = c;
  return J;
}

/// Rotates a pose covariance given in frame b into frame a (R = rotation of b in a).
inline Mat3 rotateCovariance(const Mat3& cov, double angle) {
  Mat3 R = Mat3::Identity();
  R(0, 0) = std::cos(angle); R(0, 1) = -std::sin(angle);
  R(1, 0) = std::sin(angle); R(1, 1) = std::cos(angle);
  return R * cov * R.transpose();
}

}  // namespace polarslam
