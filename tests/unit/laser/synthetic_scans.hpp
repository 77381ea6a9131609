#pragma once
// Analytic laser readings for tests and benchmarks: the range of a line at bearing φ is the
// closed form r = d / cos(α − φ) (2.10); a wall segment is a line limited to the bearings
// between its ends; a scan takes the nearest wall per beam. This is geometry, not a simulator.
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "laser/polar_line_fit.hpp"

namespace polarslam::synthetic {

inline std::vector<double> bearings(double first, double last, int count) {
  std::vector<double> b(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) b[static_cast<size_t>(i)] = first + (last - first) * i / (count - 1);
  return b;
}

/// Ranges of the infinite line (α, d) at the bearings (2.10).
inline std::vector<double> lineRanges(const PolarLine& line, const std::vector<double>& bearings) {
  std::vector<double> r;
  r.reserve(bearings.size());
  for (double b : bearings) r.push_back(lineRange(line, b));
  return r;
}

/// Line (α, d ≥ 0) through two points.
inline PolarLine lineThrough(const Vec2& a, const Vec2& b) {
  const Vec2 t = (b - a).normalized();
  Vec2 n(-t.y(), t.x());
  double d = n.dot(a);
  if (d < 0.0) {
    n = -n;
    d = -d;
  }
  return {std::atan2(n.y(), n.x()), d};
}

/// A wall segment from a to b (laser frame).
struct Wall {
  Vec2 a, b;
};

/// Range along bearing φ to the wall, +∞ when the beam misses it (closed form ray–segment).
inline double wallRange(const Wall& w, double bearing) {
  const Vec2 u(std::cos(bearing), std::sin(bearing));
  const Vec2 e = w.b - w.a;
  const double den = u.x() * e.y() - u.y() * e.x();
  if (std::abs(den) < 1e-12) return std::numeric_limits<double>::infinity();
  const double t = (w.a.x() * e.y() - w.a.y() * e.x()) / den;  // range along u
  const double s = (w.a.x() * u.y() - w.a.y() * u.x()) / den;  // position along the wall
  if (t <= 0.0 || s < 0.0 || s > 1.0) return std::numeric_limits<double>::infinity();
  return t;
}

/// A scan of walls: nearest wall per beam; beams that hit nothing or reach range_max read range_max.
inline LaserScan scanOfWalls(const std::vector<Wall>& walls, double angle_min, double angle_increment, int beams,
                             double range_max = 30.0) {
  LaserScan scan;
  scan.angle_min = angle_min;
  scan.angle_increment = angle_increment;
  scan.range_max = range_max;
  scan.ranges.resize(static_cast<size_t>(beams));
  for (int i = 0; i < beams; ++i) {
    double r = std::numeric_limits<double>::infinity();
    for (const Wall& w : walls) r = std::min(r, wallRange(w, scan.bearing(static_cast<size_t>(i))));
    scan.ranges[static_cast<size_t>(i)] = static_cast<float>(std::min(r, range_max));
  }
  return scan;
}

/// Rectangular room [x0, x1] × [y0, y1] around the laser, as four walls.
inline std::vector<Wall> room(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}}, {{x1, y0}, {x1, y1}}, {{x1, y1}, {x0, y1}}, {{x0, y1}, {x0, y0}}};
}

/// Adds white Gaussian noise to every finite reading below range_max.
inline void addNoise(LaserScan& scan, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  for (float& r : scan.ranges)
    if (std::isfinite(r) && r < scan.range_max) r = static_cast<float>(r + noise(rng));
}

}  // namespace polarslam::synthetic
