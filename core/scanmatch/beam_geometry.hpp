#pragma once
// The bearing grid of a scan (docs/algorithms.md §3.3): φ_i = angle_min + i·Δφ with Δφ > 0, taken from the
// sensor, with its cos/sin tables computed once per geometry and shared by every scan of it.
#include <cmath>
#include <cstddef>
#include <memory>
#include <numbers>
#include <vector>

namespace polarslam {

struct BeamGeometry {
  size_t size = 0;
  double angle_min = 0.0;
  double angle_increment = 0.0;  ///< > 0
  std::vector<double> cos_table, sin_table;
  std::vector<float> cos_float, sin_float;  ///< the same in single precision (projection)
  float centre_cos = 1.0f, centre_sin = 0.0f;  ///< of centre(), in single precision (projection)

  double bearing(size_t i) const { return angle_min + static_cast<double>(i) * angle_increment; }
  double fieldOfView() const { return angle_increment * static_cast<double>(size - 1); }
  /// Bearing in the middle of the field of view; projected bearings are unwrapped around it.
  double centre() const { return angle_min + 0.5 * fieldOfView(); }
};

/// Shared geometry for (size, angle_min, angle_increment); built once and cached, thread-safe.
std::shared_ptr<const BeamGeometry> beamGeometry(size_t size, double angle_min, double angle_increment);

/// atan2 to within 4e-8 rad at a fraction of the libm cost: the projection (§6) needs one per
/// reading per iteration. A degree-15 odd polynomial fitted (weighted least squares, Lawson
/// iterations) to atan on [0, 1], extended by octant symmetry.
inline double fastAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const bool steep = ay > ax;
  const double hi = steep ? ay : ax;
  const double lo = steep ? ax : ay;
  const double t = lo / (hi > 0.0 ? hi : 1.0);
  const double s = t * t;
  double p = -0.0040545670090758159;
  p = p * s + 0.021862957573908447;
  p = p * s - 0.055912327192457756;
  p = p * s + 0.096421974469683439;
  p = p * s - 0.13908629646722206;
  p = p * s + 0.1994656568628955;
  p = p * s - 0.3332986078977746;
  p = p * s + 0.99999933558099241;
  double a = p * t;
  // Octant and quadrant folds as arithmetic, not branches: the signs are unpredictable.
  a += static_cast<double>(steep) * (std::numbers::pi / 2.0 - 2.0 * a);
  a += static_cast<double>(x < 0.0) * (std::numbers::pi - 2.0 * a);
  return std::copysign(a, y);
}

}  // namespace polarslam
