#include "slam/feature_models.hpp"

#include <cmath>
#include <numbers>

namespace polarslam {

LineObservationModel observeLine(const Pose2& robot, const Vec2& map_line) {
  const double alpha_m = map_line.x(), d_m = map_line.y();
  const double c = std::cos(alpha_m), s = std::sin(alpha_m);
  LineObservationModel m;
  double alpha_r = wrapAngle(alpha_m - robot.theta);
  double d_r = d_m - robot.x * c - robot.y * s;
  if (d_r < 0.0) {
    d_r = -d_r;
    alpha_r = wrapAngle(alpha_r + std::numbers::pi);
    m.s = -1.0;
  }
  m.z = {alpha_r, d_r};
  m.H_x << 0.0, 0.0, -1.0,
           -m.s * c, -m.s * s, 0.0;
  m.H_y << 1.0, 0.0,
           m.s * (robot.x * s - robot.y * c), m.s;
  return m;
}

LineInitModel initLine(const Pose2& robot, const Vec2& observed_line) {
  const double alpha_prime = wrapAngle(robot.theta + observed_line.x());
  const double d_prime = observed_line.y() + robot.x * std::cos(alpha_prime) + robot.y * std::sin(alpha_prime);
  LineInitModel m;
  if (d_prime >= 0.0) {
    m.y = {alpha_prime, d_prime};
  } else {
    m.y = {wrapAngle(alpha_prime + std::numbers::pi), -d_prime};
    m.s = -1.0;
  }
  // Evaluated at the stored α_m: no s on the trigonometric entries (docs/algorithms.md §17.8).
  const double c = std::cos(m.y.x()), s = std::sin(m.y.x());
  const double lever = -robot.x * s + robot.y * c;
  m.G_z << 1.0, 0.0,
           lever, m.s;
  m.G_x << 0.0, 0.0, 1.0,
           c, s, lever;
  return m;
}

PointObservationModel observePoint(const Pose2& robot, const Vec2& map_point) {
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const double dx = map_point.x() - robot.x, dy = map_point.y() - robot.y;
  PointObservationModel m;
  m.z = {c * dx + s * dy, -s * dx + c * dy};
  // θ column = (y_r, −x_r)
  m.H_x << -c, -s, m.z.y(),
           s, -c, -m.z.x();
  m.H_y << c, s,
           -s, c;
  return m;
}

PointInitModel initPoint(const Pose2& robot, const Vec2& observed_point) {
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const double xr = observed_point.x(), yr = observed_point.y();
  PointInitModel m;
  m.y = {robot.x + xr * c - yr * s, robot.y + xr * s + yr * c};
  m.G_z << c, -s,
           s, c;
  m.G_x << 1.0, 0.0, -xr * s - yr * c,
           0.0, 1.0, xr * c - yr * s;
  return m;
}

CornerObservationModel observeCorner(const Pose2& robot, const Vec3& map_corner) {
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const double dx = map_corner.x() - robot.x, dy = map_corner.y() - robot.y;
  const double xr = c * dx + s * dy, yr = -s * dx + c * dy;
  const double t = dx * dx + dy * dy, root = std::sqrt(t);
  CornerObservationModel m;
  m.z = {std::atan2(yr, xr), root, wrapAngle(map_corner.z() - robot.theta)};
  if (!(root > 0.0)) return m;
  // With (x − x_m, y − y_m) = (−dx, −dy), App. B's H_x and H_y (docs/algorithms.md §17.8, erratum 5 applied).
  m.H_x << dy / t, -dx / t, -1.0,
           -dx / root, -dy / root, 0.0,
           0.0, 0.0, -1.0;
  m.H_y << -dy / t, dx / t, 0.0,
           dx / root, dy / root, 0.0,
           0.0, 0.0, 1.0;
  return m;
}

CornerInitModel initCorner(const Pose2& robot, const Vec3& observed_corner) {
  const double phi = observed_corner.x(), r = observed_corner.y();
  const double heading = robot.theta + phi;
  const double c = std::cos(heading), s = std::sin(heading);
  CornerInitModel m;
  m.y = {robot.x + r * c, robot.y + r * s, wrapAngle(robot.theta + observed_corner.z())};
  m.G_z << -r * s, c, 0.0,
           r * c, s, 0.0,
           0.0, 0.0, 1.0;
  m.G_x << 1.0, 0.0, -r * s,
           0.0, 1.0, r * c,
           0.0, 0.0, 1.0;
  return m;
}

PolarCorner cornerToPolar(const Vec3& cartesian) {
  const double x = cartesian.x(), y = cartesian.y();
  const double r2 = x * x + y * y, r = std::sqrt(r2);
  PolarCorner p;
  p.z = {std::atan2(y, x), r, cartesian.z()};
  if (!(r > 0.0)) return p;
  p.J << -y / r2, x / r2, 0.0,
         x / r, y / r, 0.0,
         0.0, 0.0, 1.0;
  return p;
}

Vec3 observationDifference(MapFeatureKind kind, const Vec3& a, const Vec3& b) {
  Vec3 d = a - b;
  switch (kind) {
    case MapFeatureKind::Line: d.x() = wrapAngle(d.x()); d.z() = 0.0; break;
    case MapFeatureKind::Corner: d.x() = wrapAngle(d.x()); d.z() = wrapAngle(d.z()); break;
    case MapFeatureKind::Point: d.z() = 0.0; break;
  }
  return d;
}

}  // namespace polarslam
