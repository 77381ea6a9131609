#include "laser/laser_error_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace polarslam {
namespace {

/// Mean over one quantisation step of the quantiser's output variance (2.5).
double phaseAveragedQuantizerVariance(double quantum, double noise_sigma) {
  constexpr int kSamples = 64;
  double sum = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double r = 10.0 * quantum + quantum * (i + 0.5) / kSamples;
    sum += quantizerErrorVariance(r, quantum, noise_sigma);
  }
  return sum / kSamples;
}

}  // namespace

SensorMotion sensorMotionFromBaseTwist(const Pose2& mount, double v, double omega) {
  // Velocity of the laser origin in the base frame: v·x̂ + ω ẑ × (mount position).
  const double vbx = v - omega * mount.y;
  const double vby = omega * mount.x;
  const double c = std::cos(mount.theta), s = std::sin(mount.theta);
  return {c * vbx + s * vby, -s * vbx + c * vby, omega};
}

LaserErrorModel::LaserErrorModel(const LaserErrorParams& params) : params_(params) {
  const RangeErrorParams& r = params.range;
  const double quantizer_variance =
      r.quantum > 0.0 ? phaseAveragedQuantizerVariance(r.quantum, r.noise_sigma) : r.noise_sigma * r.noise_sigma;
  const double sigma = std::sqrt(quantizer_variance + params.output_noise_sigma * params.output_noise_sigma);
  range_sigma_ = std::max(sigma, params.min_range_sigma);
  quantization_amplitude_ = quantizationBiasAmplitude(r.quantum, r.noise_sigma);
  max_incidence_tan_ = std::tan(std::clamp(r.max_incidence, 0.0, 1.5707));
  tilt_axis_cos_ = std::cos(params.tilt_axis);
  tilt_axis_sin_ = std::sin(params.tilt_axis);
}

double incidenceAnglePerturbation(double alpha, double bearing, double w, double max_incidence) {
  const double beta = std::min(std::abs(wrapAngle(alpha - bearing)), max_incidence);
  return w * std::abs(std::tan(beta));  // (2.8), third term
}

double distanceGrowthPerturbation(double range, double line_min_range, double k) {
  return k * (range - line_min_range);  // (2.8), second term
}

double quantizationPerturbation(double range, double quantum, double amplitude, double phase) {
  if (quantum <= 0.0) return 0.0;
  return amplitude * std::sin(2.0 * std::numbers::pi * (range - quantize(range, quantum)) / quantum + phase);  // (2.6)
}

double planeTiltPerturbation(double alpha, double bearing, double range, double tilt, double tilt_axis) {
  const double cos_incidence = std::cos(alpha - bearing);
  return range * 0.5 * tilt * tilt *
         (1.0 - std::cos(bearing - tilt_axis) * std::cos(alpha - tilt_axis) / cos_incidence);
}

double motionPerturbation(double alpha, double d, double bearing, double time, const SensorMotion& m) {
  const double c = std::cos(alpha - bearing), s = std::sin(alpha - bearing);
  const double normal_shift = (std::cos(alpha) * m.vx + std::sin(alpha) * m.vy) * time;  // n·δp
  const double turn = m.omega * time;                                                    // δφ
  return -normal_shift / c - d * s / (c * c) * turn;
}

ReadingPerturbations readingPerturbations(const LaserErrorModel& model, const ReadingGeometry& g,
                                          double line_min_range, double time, const SensorMotion& motion) {
  const LaserErrorParams& p = model.params();
  const double c = g.cos_incidence, s = g.sin_incidence;
  ReadingPerturbations xi;
  if (p.range.incidence != 0.0)  // w|tan β|, |β| clamped   (2.8)
    xi.incidence = p.range.incidence * std::min(std::abs(s / c), model.maxIncidenceTan());
  if (p.range.growth != 0.0) xi.growth = distanceGrowthPerturbation(g.range, line_min_range, p.range.growth);
  if (p.range.quantum > 0.0 && model.quantizationAmplitude() > 1e-7) {  // b·sin(θ), b·sin(θ + π/2)   (2.6)
    const double theta = 2.0 * std::numbers::pi * (g.range - quantize(g.range, p.range.quantum)) / p.range.quantum;
    xi.quantization_sin = model.quantizationAmplitude() * std::sin(theta);
    xi.quantization_cos = model.quantizationAmplitude() * std::cos(theta);
  }
  if (p.tilt == 0.0 && motion.isZero()) return xi;
  // cos α, sin α of the line from α = β + φ.
  const double ca = c * g.cos_bearing - s * g.sin_bearing, sa = s * g.cos_bearing + c * g.sin_bearing;
  if (p.tilt != 0.0) {
    const double cos_bearing_axis = g.cos_bearing * model.tiltAxisCos() + g.sin_bearing * model.tiltAxisSin();
    const double cos_normal_axis = ca * model.tiltAxisCos() + sa * model.tiltAxisSin();
    xi.tilt = g.range * 0.5 * p.tilt * p.tilt * (1.0 - cos_bearing_axis * cos_normal_axis / c);
  }
  if (!motion.isZero()) {
    const double normal_shift = (ca * motion.vx + sa * motion.vy) * time;
    xi.motion = -normal_shift / c - g.d * s / (c * c) * motion.omega * time;
  }
  return xi;
}

}  // namespace polarslam
