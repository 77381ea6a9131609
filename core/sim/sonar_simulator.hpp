#pragma once
// Simulated advanced sonar array (docs/algorithms.md §17.2–17.3): targets classified plane / corner / edge
// with range and bearing errors of about 1 mm and 0.1°.
//  - plane: specular, so the echo returns along the wall's normal: seen only when the foot of
//    the perpendicular from the array lies on the wall and within the field of view; range =
//    normal distance, bearing = normal direction;
//  - corner: the apex of a concave right angle seen from inside (double reflection);
//  - edge: a convex vertex or the free end of a wall (diffraction), including small features;
//  - unknown: only through misclassification or spurious returns.
// Glass reflects sound; absorbing surfaces give no echo and hide what lies behind them.
#include <cstdint>
#include <vector>

#include "sim/random.hpp"
#include "robot/robot_description.hpp"
#include "sim/world.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

/// A noise-free target as the array would report it, and the world element that caused it.
struct TrueSonarTarget {
  SonarKind kind = SonarKind::Unknown;
  double range = 0.0, bearing = 0.0;  ///< in the array frame
  int segment = -1;                   ///< plane: the reflecting segment
  int vertex = -1;                    ///< corner/edge: index into World::vertices()
};

class SonarSimulator {
 public:
  SonarSimulator(const SonarConfig& config, uint64_t seed);

  /// Every target visible from an array at world pose `array_pose`, sorted by range.
  static std::vector<TrueSonarTarget> visibleTargets(const World& world, const SonarConfig& config,
                                                     const Pose2& array_pose);

  /// One measurement cycle at `utime` with the robot at `robot_pose`: visible targets with
  /// noise, misses and misclassifications, plus spurious returns.
  SonarScan scan(const World& world, int64_t utime, const Pose2& robot_pose);

  const SonarConfig& config() const { return config_; }

 private:
  SonarTarget measure(const TrueSonarTarget& truth);
  SonarTarget spuriousTarget();
  SonarKind otherKind(SonarKind kind);

  SonarConfig config_;
  Rng rng_;
  int64_t seq_ = 0;
};

}  // namespace polarslam
