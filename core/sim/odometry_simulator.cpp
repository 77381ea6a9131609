#include "sim/odometry_simulator.hpp"

#include <cmath>

namespace polarslam {

OdometrySimulator::OdometrySimulator(const OdometryConfig& odometry, const DriveConfig& robot, uint64_t seed)
    : config_(odometry), rng_(seed) {
  model_.wheelbase = robot.wheel_base * (1.0 + odometry.wheel_base_error);
  model_.k_left = odometry.k_left;
  model_.k_right = odometry.k_right;
}

OdometryReading OdometrySimulator::measure(int64_t utime, const WheelTravel& true_travel, double dt) {
  const double true_left = true_travel.left - last_true_.left;
  const double true_right = true_travel.right - last_true_.right;
  last_true_ = true_travel;
  // Encoders count wheel turns; odometry multiplies by the nominal radius. A wheel whose true
  // radius is nominal·(1 + e) therefore reports its travel divided by (1 + e).
  const double ds_left = rng_.normal(true_left / (1.0 + config_.left_radius_error),
                                     std::sqrt(config_.k_left * std::abs(true_left)));
  const double ds_right = rng_.normal(true_right / (1.0 + config_.right_radius_error),
                                      std::sqrt(config_.k_right * std::abs(true_right)));
  measured_.left += ds_left;
  measured_.right += ds_right;
  propagateWheelStep(pose_, cov_, ds_right, ds_left, model_);  // docs/algorithms.md §17.6

  OdometryReading r;
  r.utime = utime;
  r.seq = seq_++;
  r.pose = pose_;
  r.cov = cov_;
  r.left_travel = measured_.left;
  r.right_travel = measured_.right;
  if (dt > 0.0) {
    r.v = 0.5 * (ds_left + ds_right) / dt;
    r.omega = (ds_right - ds_left) / model_.wheelbase / dt;
  }
  return r;
}

}  // namespace polarslam
