#pragma once
// Turns simulator output into LCM messages on the configured channels, numbering each
// channel's messages; `Emit` decides where they go (UDP publish or a log file).
#include <string>
#include <utility>

#include "common/lcm_convert.hpp"
#include "sim/simulator.hpp"

namespace polarslam {

struct SensorChannels {
  std::string laser = "LASER", sonar = "SONAR", odometry = "ODOMETRY", ground_truth = "GROUND_TRUTH";
};

/// Emit: callable (const std::string& channel, int64_t utime, const Msg& msg) for any LCM type.
template <typename Emit>
class SimChannels : public SimSink {
 public:
  SimChannels(SensorChannels channels, Emit emit) : channels_(std::move(channels)), emit_(std::move(emit)) {}

  void onLaser(const LaserScan& scan) override {
    auto msg = toLcm(scan);
    msg.seq = laser_seq_++;
    emit_(channels_.laser, scan.utime, msg);
  }
  void onSonar(const SonarScan& scan) override {
    auto msg = toLcm(scan);
    msg.seq = sonar_seq_++;
    emit_(channels_.sonar, scan.utime, msg);
  }
  void onOdometry(const OdometryReading& odometry) override {
    auto msg = toLcm(odometry);
    msg.seq = odometry_seq_++;
    emit_(channels_.odometry, odometry.utime, msg);
  }
  void onGroundTruth(const PoseStamped& pose) override {
    emit_(channels_.ground_truth, pose.utime, toLcm(pose, "world", truth_seq_++));
  }
  int64_t messages() const { return laser_seq_ + sonar_seq_ + odometry_seq_ + truth_seq_; }

 private:
  SensorChannels channels_;
  Emit emit_;
  int64_t laser_seq_ = 0, sonar_seq_ = 0, odometry_seq_ = 0, truth_seq_ = 0;
};

template <typename Emit>
SimChannels<Emit> makeSimChannels(SensorChannels channels, Emit emit) {
  return SimChannels<Emit>(std::move(channels), std::move(emit));
}

}  // namespace polarslam
