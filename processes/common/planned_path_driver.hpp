#pragma once
// Drives the simulated robot along planned paths (PLANNED_PATH, map frame): the robot knows its
// place in the map only through its SLAM pose, so the path is re-expressed around the robot from
// that pose (core/grid/path_tracker.hpp) and handed to the simulator's own path follower, at
// most every `period_s` of simulated time. Without SLAM, the robot's start frame stands in for
// the map frame (a perfect localiser).
#include <optional>
#include <utility>
#include <vector>

#include "grid/path_tracker.hpp"
#include "sim/simulator.hpp"

namespace polarslam {

class PlannedPathDriver {
 public:
  explicit PlannedPathDriver(Simulator& sim, double period_s = 0.1)
      : sim_(sim), start_(sim.truePose()), period_s_(period_s) {}

  /// A new plan (map frame); replaces the simulator's path from the next pose on.
  void onPath(std::vector<Vec2> map_waypoints) {
    tracker_.setPath(std::move(map_waypoints));
    stopped_ = false;
    last_update_ = -1e9;
    if (last_map_pose_) onMapPose(*last_map_pose_);
  }

  /// The robot's SLAM pose (map frame).
  void onMapPose(const Pose2& map_pose) {
    last_map_pose_ = map_pose;
    if (tracker_.path().empty() || stopped_ || sim_.time() - last_update_ < period_s_) return;
    last_update_ = sim_.time();
    std::vector<Vec2> path = tracker_.update(map_pose, sim_.truePose());
    if (tracker_.goalReached()) {
      stopped_ = true;
      path.clear();  // stand still at the goal
    }
    sim_.setPath(path);
  }

  /// Without SLAM: the true pose in the robot's start frame.
  void useTruePose() { onMapPose(start_.inverse() * sim_.truePose()); }

  bool following() const { return !tracker_.path().empty() && !stopped_; }
  bool goalReached() const { return tracker_.goalReached(); }

 private:
  Simulator& sim_;
  Pose2 start_;
  double period_s_;
  PathTracker tracker_;
  std::optional<Pose2> last_map_pose_;
  double last_update_ = -1e9;
  bool stopped_ = false;
};

}  // namespace polarslam
