#pragma once
// Driving to a goal on a growing map (thesis §3.7.1): a goal is planned on the latest grid from
// the robot's latest SLAM pose, re-planned on every newer grid (the map grows, a goal in unknown
// space becomes reachable), and dropped once the robot is within the tolerance of it. This is
// polarslam-grid's GOAL → PLANNED_PATH logic, in core so that it is tested without LCM.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "grid/planner.hpp"

namespace polarslam {

/// A plan to publish.
struct GoalPlan {
  std::vector<Vec2> waypoints;  ///< map frame, from the robot to the goal (or the nearest reachable cell)
  bool goal_exact = false;
  int64_t goal_utime = 0;       ///< the goal's time stamp, so the follower knows which goal it serves
};

class GoalPlanner {
 public:
  explicit GoalPlanner(PlannerOptions planner = {}, double goal_tolerance = 0.2);

  /// A new goal (map frame; theta unused). Returns "" and a plan if it can plan now; a goal with a
  /// non-finite or absurd position is refused with the reason.
  std::string setGoal(const Vec2& goal, int64_t utime, std::optional<GoalPlan>& plan);
  /// The robot's newest pose. True when this pose reached the goal (the goal is dropped).
  bool updateRobot(const Pose2& pose);
  /// A newer grid: re-plans toward the goal, if there is one.
  std::optional<GoalPlan> updateGrid(const GridSlice& slice);

  bool hasGoal() const { return goal_.has_value(); }
  bool hasGrid() const { return slice_.has_value(); }
  /// "none", "waiting for a grid", "planned", "planned to nearest reachable point", "failed: …", "reached".
  const std::string& state() const { return state_; }
  double planLength() const { return plan_length_; }

 private:
  std::optional<GoalPlan> plan();

  PlannerOptions planner_;
  double goal_tolerance_;
  std::optional<Vec2> goal_;
  int64_t goal_utime_ = 0;
  std::optional<Pose2> robot_;
  std::optional<GridSlice> slice_;
  std::string state_ = "none";
  double plan_length_ = 0.0;
};

}  // namespace polarslam
