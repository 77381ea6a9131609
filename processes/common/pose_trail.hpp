#pragma once
// What viewers draw as a trajectory: a pose stream thinned to poses at least 5 cm or 0.1 rad
// apart, bounded in length (the oldest half is thinned when full), so that sending it whole
// stays cheap however long the run.
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "geometry/pose2.hpp"

namespace polarslam {

class PoseTrail {
 public:
  static constexpr double kMinStep = 0.05, kMinTurn = 0.1;  // m, rad
  explicit PoseTrail(size_t capacity = 20000) : capacity_(capacity < 4 ? 4 : capacity) {}

  void add(const PoseStamped& pose, const std::string& frame);
  const std::vector<Pose2>& poses() const { return poses_; }
  int64_t utime() const { return utime_; }
  const std::string& frame() const { return frame_; }
  /// True once after poses were added or changed.
  bool takeChanged();

 private:
  size_t capacity_;
  std::vector<Pose2> poses_;
  int64_t utime_ = 0;
  std::string frame_ = "map";
  bool changed_ = false;
};

/// The points as poses, each heading towards the next (the last keeps its predecessor's heading).
std::vector<Pose2> headingsAlong(const std::vector<Vec2>& points);

}  // namespace polarslam
