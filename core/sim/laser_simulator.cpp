#include "sim/laser_simulator.hpp"

#include <cmath>
#include <limits>
#include <unordered_map>

namespace polarslam {
namespace {

struct TrueBeam {
  double range = -1.0;  ///< slant range r', < 0 for no return
  double incidence = 0.0;
  int surface = -1;
};

}  // namespace

LaserSimulator::LaserSimulator(const LaserConfig& config, uint64_t seed) : config_(config), rng_(seed) {}

double LaserSimulator::tiltedRange(double horizontal_range, double bearing) const {
  if (config_.tilt == 0.0) return horizontal_range;
  const double elevation = config_.tilt * std::sin(bearing - config_.tilt_axis);  // docs/algorithms.md §16.10
  return horizontal_range / std::cos(elevation);
}

double LaserSimulator::measureRange(double true_range, double surface_min_range, double incidence,
                                    double scan_bias) {
  const RangeErrorParams& e = config_.errors;
  // r_b + k(r' − r_min) + w|tan β| plus this scan's random bias   (2.8)
  double r = true_range + scan_bias + systematicRangeBias(e, true_range, surface_min_range, incidence);
  r = rng_.normal(r, e.noise_sigma);  // receiver noise r_nr ~ N(0, σ_n²) before the quantiser
  r = quantize(r, e.quantum);         // truncating quantiser Q   (2.1)
  if (config_.compensate_quantizer_offset) r += 0.5 * e.quantum;  // removes the −q_r/2 of (2.6)
  return rng_.normal(r, config_.output_noise_sigma);  // optional extra white noise r_n
}

LaserScan LaserSimulator::scan(const World& world, int64_t utime,
                               const std::function<Pose2(double)>& robot_pose_at) {
  const LaserConfig& c = config_;
  LaserScan scan;
  scan.utime = utime;
  scan.seq = seq_++;
  scan.angle_min = c.angle_min;
  scan.angle_increment = c.angleIncrement();
  scan.time_increment = c.time_increment;
  scan.range_max = c.range_max;
  scan.laser_pose = c.mount;

  std::vector<TrueBeam> beams(static_cast<size_t>(c.beams));
  std::unordered_map<int, double> surface_min_range;  // r_min per surface in this scan
  for (int i = 0; i < c.beams; ++i) {
    const Pose2 laser = robot_pose_at(i * c.time_increment) * c.mount;  // this beam's own time
    const double bearing = scan.bearing(static_cast<size_t>(i));
    const RayHit hit = world.castRay(laser.translation(), laser.theta + bearing, c.range_max, Sensor::Laser);
    if (!hit.hit || !hit.echo) continue;
    TrueBeam& b = beams[static_cast<size_t>(i)];
    b.range = tiltedRange(hit.range, bearing);
    b.incidence = hit.incidence;
    b.surface = world.segments()[static_cast<size_t>(hit.segment)].surface;
    auto [it, inserted] = surface_min_range.try_emplace(b.surface, b.range);
    if (!inserted) it->second = std::min(it->second, b.range);
  }

  const double scan_bias = drawScanBias();
  constexpr float kNoReturn = std::numeric_limits<float>::infinity();
  scan.ranges.assign(beams.size(), kNoReturn);
  for (size_t i = 0; i < beams.size(); ++i) {
    const TrueBeam& b = beams[i];
    if (b.range < 0.0) continue;
    const double r = measureRange(b.range, surface_min_range[b.surface], b.incidence, scan_bias);
    if (r > 0.0 && r < c.range_max) scan.ranges[i] = static_cast<float>(r);
  }
  return scan;
}

}  // namespace polarslam
