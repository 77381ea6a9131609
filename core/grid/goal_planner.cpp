#include "grid/goal_planner.hpp"

#include <cmath>

namespace polarslam {
namespace {

constexpr double kMaxGoalCoordinate = 1e6;  // m: beyond any map

}  // namespace

GoalPlanner::GoalPlanner(PlannerOptions planner, double goal_tolerance)
    : planner_(planner), goal_tolerance_(goal_tolerance) {
  planner_.comfort_distance = std::max(planner_.comfort_distance, 2.0 * planner_.robot_radius);
}

std::string GoalPlanner::setGoal(const Vec2& goal, int64_t utime, std::optional<GoalPlan>& out) {
  out.reset();
  if (!goal.allFinite() || goal.cwiseAbs().maxCoeff() > kMaxGoalCoordinate) return "goal: non-finite or absurd position";
  goal_ = goal;
  goal_utime_ = utime;
  if (!slice_) {
    state_ = "waiting for a grid";
    return {};
  }
  out = plan();
  return {};
}

bool GoalPlanner::updateRobot(const Pose2& pose) {
  robot_ = pose;
  if (!goal_ || (pose.translation() - *goal_).norm() >= goal_tolerance_) return false;
  goal_.reset();
  state_ = "reached";
  return true;
}

std::optional<GoalPlan> GoalPlanner::updateGrid(const GridSlice& slice) {
  slice_ = slice;
  return goal_ ? plan() : std::nullopt;
}

std::optional<GoalPlan> GoalPlanner::plan() {
  if (!robot_) {
    state_ = "failed: no SLAM pose yet";
    return std::nullopt;
  }
  const PlanResult result = planPath(*slice_, robot_->translation(), *goal_, planner_);
  plan_length_ = result.length;
  if (!result.found) {
    state_ = "failed: " + result.failure;
    return std::nullopt;
  }
  state_ = result.goal_exact ? "planned" : "planned to nearest reachable point";
  return GoalPlan{result.waypoints, result.goal_exact, goal_utime_};
}

}  // namespace polarslam
