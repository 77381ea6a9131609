#pragma once
// PSM SLAM driven by the simulator in tests: a sink feeding it, a run over a world file, and the
// check scripts/bench-slam makes of the graph's edges against the truth.
#include <cmath>
#include <string>
#include <vector>

#include "eval/trajectory_lookup.hpp"
#include "robot/robot_description.hpp"
#include "sim/simulator.hpp"
#include "slam/psm_slam.hpp"

namespace polarslam::testing {

class PsmSlamSimSink : public SimSink {
 public:
  explicit PsmSlamSimSink(PsmSlam& slam) : slam_(slam) {}
  void onLaser(const LaserScan& scan) override { slam_.addScan(scan); }
  void onSonar(const SonarScan&) override {}
  void onOdometry(const OdometryReading& odometry) override { slam_.addOdometry(odometry); }
  void onGroundTruth(const PoseStamped& pose) override { truth.push_back(pose); }
  std::vector<PoseStamped> truth;

 private:
  PsmSlam& slam_;
};

/// Simulates `world_file` (config/worlds/) with the default robot and `seed` into `sink`.
inline void simulatePsmSlam(const std::string& world_file, uint64_t seed, PsmSlamSimSink& sink) {
  const World world = loadWorld(std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/" + world_file);
  const RobotDescription robot = loadRobotDescription(std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml");
  Simulator sim(world, robot, seed);
  while (!sim.finished() && sim.time() < 600.0) sim.step(sink);
}

/// Active edges of `kind` off the truth as scripts/bench-slam counts them: more than 0.3 m or 5°
/// from the true relative pose of their nodes (`truth` by time, in any fixed frame), and farther
/// than their covariance allows (χ²₃(0.999)): along a corridor a match may be off by more and say so.
inline size_t edgesOffTheTruth(const PoseGraph& graph, const std::vector<PoseStamped>& truth, PoseGraphEdgeKind kind) {
  const TrajectoryLookup lookup(truth);
  size_t off = 0;
  for (const PoseGraphEdge& e : graph.edges()) {
    if (e.kind != kind || !e.active) continue;
    const auto a = lookup.interpolate(graph.node(e.from).utime, 100000);
    const auto b = lookup.interpolate(graph.node(e.to).utime, 100000);
    if (!a || !b) continue;
    const Pose2 miss = between(between(*a, *b), e.measurement);
    if ((miss.translation().norm() > 0.3 || std::abs(miss.theta) > deg2rad(5.0)) && edgeChiSquared(*a, *b, e) > 16.27) ++off;
  }
  return off;
}

}  // namespace polarslam::testing
