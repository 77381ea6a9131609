#pragma once
// A simulator sink that feeds one estimator and keeps the ground truth: tests and benchmarks that
// run an estimator over a simulated world in-process (no LCM).
#include <vector>

#include "pipeline/estimator.hpp"
#include "sim/simulator.hpp"

namespace polarslam::testing {

class EstimatorSimSink : public SimSink {
 public:
  explicit EstimatorSimSink(Estimator& estimator) : estimator_(estimator) {}
  void onLaser(const LaserScan& scan) override { estimator_.onLaser(scan); }
  void onSonar(const SonarScan& scan) override { estimator_.onSonar(scan); }
  void onOdometry(const OdometryReading& odometry) override { estimator_.onOdometry(odometry); }
  void onGroundTruth(const PoseStamped& pose) override { truth.push_back(pose); }
  std::vector<PoseStamped> truth;

 private:
  Estimator& estimator_;
};

}  // namespace polarslam::testing
