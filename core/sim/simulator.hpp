#pragma once
// The simulated robot: a world of walls with materials, a differential-drive robot following
// waypoints, and honest laser, advanced-sonar and odometry sensors. Deterministic for a seed.
//
// CONTRACT used by processes/polarslam-sim and `polarslam simulate` (keep these signatures):
//   World world = loadWorld("config/worlds/office.yaml");
//   RobotDescription cfg = loadRobotDescription("config/robots/default.yaml");   // robot + sensors
//   Simulator sim(world, cfg, seed);
//   while (sim.time() < seconds && !sim.finished()) sim.step(sink);   // emits events in time order
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"
#include "sonar/sonar_targets.hpp"
#include "robot/robot_description.hpp"
#include "sim/world.hpp"

namespace polarslam {

/// Receives simulator output in time order.
class SimSink {
 public:
  virtual ~SimSink() = default;
  virtual void onLaser(const LaserScan& scan) = 0;
  virtual void onSonar(const SonarScan& scan) = 0;
  virtual void onOdometry(const OdometryReading& odometry) = 0;
  virtual void onGroundTruth(const PoseStamped& pose) = 0;
};

class Simulator {
 public:
  Simulator(World world, RobotDescription config, uint64_t seed);
  ~Simulator();
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;

  /// Advances one control period and emits every sensor event that fell due.
  void step(SimSink& sink);
  /// Seconds of simulated time since start.
  double time() const;
  /// Microsecond timestamp of the current simulated time.
  int64_t utime() const;
  /// True once the robot reached the last waypoint of its path (and the path does not loop).
  bool finished() const;
  /// Replaces the remaining path (e.g. a planner's path to a GOAL); world frame, metres.
  void setPath(const std::vector<Vec2>& waypoints);
  /// True pose of the robot base in the world frame.
  Pose2 truePose() const;
  const World& world() const;
  const RobotDescription& config() const;

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace polarslam
