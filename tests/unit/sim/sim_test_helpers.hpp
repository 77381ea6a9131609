#pragma once
// Shared fixtures for the simulator tests.
#include <string>
#include <vector>

#include "sim/simulator.hpp"
#include "source_path.hpp"

namespace polarslam::test {

using testing::sourcePath;

/// Keeps every event, plus one line per event in emission order (for determinism checks).
struct RecordingSink : SimSink {
  std::vector<LaserScan> lasers;
  std::vector<SonarScan> sonars;
  std::vector<OdometryReading> odometry;
  std::vector<PoseStamped> truth;
  std::vector<int64_t> event_times;

  void onLaser(const LaserScan& s) override { lasers.push_back(s); event_times.push_back(s.utime); }
  void onSonar(const SonarScan& s) override { sonars.push_back(s); event_times.push_back(s.utime); }
  void onOdometry(const OdometryReading& o) override { odometry.push_back(o); event_times.push_back(o.utime); }
  void onGroundTruth(const PoseStamped& p) override { truth.push_back(p); event_times.push_back(p.utime); }
};

/// A config whose sensors are exact: no range errors, no sonar noise, no odometry noise.
inline RobotDescription exactConfig() {
  RobotDescription c;
  c.laser.errors = RangeErrorParams{};
  c.laser.errors.max_incidence = deg2rad(80.0);
  c.laser.compensate_quantizer_offset = false;
  c.odometry.k_left = c.odometry.k_right = 0.0;
  for (SonarConfig& s : c.sonars) {
    s.range_sigma = s.bearing_sigma = 0.0;
    s.misclassification_rate = s.spurious_rate = s.miss_rate = 0.0;
  }
  return c;
}

/// Runs until `seconds` of simulated time or the end of the path.
inline RecordingSink run(Simulator& sim, double seconds) {
  RecordingSink sink;
  while (sim.time() < seconds && !sim.finished()) sim.step(sink);
  return sink;
}

}  // namespace polarslam::test
