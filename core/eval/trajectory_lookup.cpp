#include "eval/trajectory_lookup.hpp"

#include <algorithm>
#include <cstdlib>

namespace polarslam {
namespace {

/// |a − b| without overflow, whatever the two stamps (a corrupt one may be near INT64_MIN).
uint64_t gap(int64_t a, int64_t b) {
  return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b) : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

}  // namespace

TrajectoryLookup::TrajectoryLookup(std::vector<PoseStamped> poses) : poses_(std::move(poses)) {
  std::stable_sort(poses_.begin(), poses_.end(),
                   [](const PoseStamped& a, const PoseStamped& b) { return a.utime < b.utime; });
}

const PoseStamped* TrajectoryLookup::nearest(int64_t t, int64_t max_difference_us) const {
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), t,
                                      [](const PoseStamped& p, int64_t time) { return p.utime < time; });
  const PoseStamped* best = nullptr;
  if (after != poses_.end()) best = &*after;
  if (after != poses_.begin()) {
    const PoseStamped* before = &*std::prev(after);
    // On a tie, the earlier pose wins; with equal timestamps, lower_bound already chose the first.
    if (!best || gap(t, before->utime) <= gap(best->utime, t)) {
      const auto first_equal = std::lower_bound(poses_.begin(), poses_.end(), before->utime,
                                                [](const PoseStamped& p, int64_t time) { return p.utime < time; });
      best = &*first_equal;
    }
  }
  if (!best || gap(best->utime, t) > static_cast<uint64_t>(std::max<int64_t>(0, max_difference_us))) return nullptr;
  return best;
}

std::optional<Pose2> TrajectoryLookup::interpolate(int64_t t, int64_t max_difference_us) const {
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), t,
                                      [](const PoseStamped& p, int64_t time) { return p.utime < time; });
  if (after != poses_.end() && after->utime == t) return after->pose;
  if (after != poses_.end() && after != poses_.begin()) {
    const PoseStamped& a = *std::prev(after);
    const PoseStamped& b = *after;
    const auto limit = static_cast<uint64_t>(std::max<int64_t>(0, max_difference_us));
    if (gap(t, a.utime) <= limit && gap(b.utime, t) <= limit) {
      const double s = static_cast<double>(t - a.utime) / static_cast<double>(b.utime - a.utime);
      return Pose2(a.pose.x + s * (b.pose.x - a.pose.x), a.pose.y + s * (b.pose.y - a.pose.y),
                   wrapAngle(a.pose.theta + s * wrapAngle(b.pose.theta - a.pose.theta)));
    }
  }
  const PoseStamped* closest = nearest(t, max_difference_us);
  if (!closest) return std::nullopt;
  return closest->pose;
}

}  // namespace polarslam
