#pragma once
// Time look-up in a trajectory: nearest pose within a tolerance, or interpolation between the
// poses on either side. Real logs are not always time-ordered (docs/algorithms.md §20.3), so the poses are
// sorted here, for look-up only (stable: of equal timestamps, the first one written wins).
#include <cstdint>
#include <optional>
#include <vector>

#include "geometry/features.hpp"

namespace polarslam {

class TrajectoryLookup {
 public:
  explicit TrajectoryLookup(std::vector<PoseStamped> poses);

  /// The pose closest in time to t if it lies within max_difference_us, else nullptr.
  const PoseStamped* nearest(int64_t t, int64_t max_difference_us) const;

  /// The pose at t, linearly interpolated (angle along the shorter arc) between the poses on
  /// either side when both lie within max_difference_us of t; else the nearest within that
  /// tolerance; else nullopt.
  std::optional<Pose2> interpolate(int64_t t, int64_t max_difference_us) const;

  const std::vector<PoseStamped>& poses() const { return poses_; }
  bool empty() const { return poses_.empty(); }

 private:
  std::vector<PoseStamped> poses_;
};

}  // namespace polarslam
