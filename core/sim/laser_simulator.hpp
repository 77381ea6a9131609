#pragma once
// Simulated time-of-flight laser scanner. Each beam is measured at its own time while the
// robot moves (motion distortion), from the laser's mount pose, and every reading goes through
// the range error model of thesis §2.2:
//   Δr ≈ r_b + k(r' − r_min) + w|tan β| + b·sin(2π(r' − Q(r'))/q_r) + r_n      (2.8)
// The quantisation bias b·sin(…) and the quantiser's noise are not added as formulas: they
// arise, as in the thesis's derivation (2.1)–(2.7), from Gaussian noise entering a truncating
// quantiser. A tilted scan plane lengthens readings of vertical walls by r(1/cos e − 1).
#include <cstdint>
#include <functional>

#include "laser/laser_scan.hpp"
#include "sim/random.hpp"
#include "robot/robot_description.hpp"
#include "sim/world.hpp"

namespace polarslam {

class LaserSimulator {
 public:
  LaserSimulator(const LaserConfig& config, uint64_t seed);

  /// One scan whose beam 0 is measured at `utime`. `robot_pose_at(τ)` gives the robot's true
  /// pose τ seconds after `utime` (beam i is measured at τ = i·time_increment).
  LaserScan scan(const World& world, int64_t utime, const std::function<Pose2(double)>& robot_pose_at);

  /// A reading of true (slant) range r' through (2.8) and the quantiser (2.1). `surface_min_range`
  /// is r_min, the shortest true range to the same surface in this scan; `incidence` is β.
  double measureRange(double true_range, double surface_min_range, double incidence, double scan_bias);

  /// Range along a beam at bearing φ of a tilted scan plane to a vertical wall whose horizontal
  /// distance along the beam is `horizontal_range`: r/cos e with e = ε·sin(φ − ψ).
  double tiltedRange(double horizontal_range, double bearing) const;

  /// Draws the random bias of one scan, N(0, scan_bias_sigma²).
  double drawScanBias() { return rng_.normal(0.0, config_.errors.scan_bias_sigma); }

  const LaserConfig& config() const { return config_; }

 private:
  LaserConfig config_;
  Rng rng_;
  int64_t seq_ = 0;
};

}  // namespace polarslam
