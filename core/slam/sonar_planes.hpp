#pragma once
// The advanced sonar's planes filled into a laser scan, for PSM SLAM on robots that carry both
// (thesis chapter 3's fusion idea applied to scan matching; docs/algorithms.md §18): sound
// reflects off glass, the laser passes through it, so a glass corridor leaves the laser blind
// while the sonar still reports its walls. A plane target gives the wall's line (the echo returns
// along its normal, docs/algorithms.md §17.3) but not its extent, so only beams that meet the line
// within `half_extent` of the echo's foot point are filled, and only where the laser saw nothing
// or something farther (behind the glass), and only for walls the laser does not see itself
// (else a plane would paint over doorways). Spurious echoes come and go; only a plane the same
// array reported in its previous scan as well (after the robot's motion) is used.
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "sonar/sonar_targets.hpp"

namespace polarslam {

/// A wall the sonar saw, in the robot base frame of the sonar scan's time.
struct SonarPlane {
  Vec2 foot;    ///< m: where the echo's normal meets the wall
  Vec2 normal;  ///< unit, from the array towards the wall
};

struct SonarPlaneFillOptions {
  double half_extent = 1.0;  ///< m along the wall either side of the foot point
  double margin = 0.1;       ///< m: a laser reading this much beyond the wall is behind it
  double repeat_distance = 0.05;          ///< m: a plane seen again lies this close to its line
  double repeat_angle = deg2rad(3.0);     ///< ... and turned at most this much
  /// A plane the laser itself sees along more than this fraction of the beams that meet it is
  /// no glass, and is not filled.
  double laser_seen_fraction = 0.2;
  /// Only a scan whose laser returns (within the matcher's range) on fewer than this fraction of
  /// its beams is filled: where the laser sees enough, its own view stays as it is (sonar sees a
  /// glass wall from some places and not from others, and reference scans that differ so match
  /// worse; a corridor of glass leaves the laser next to nothing).
  double max_return_fraction = 0.5;
};

/// The plane targets of one sonar scan (other kinds and unusable targets are skipped).
std::vector<SonarPlane> sonarPlanes(const SonarScan& scan);
/// The plane seen from a robot pose `motion` ahead (motion: the later pose in the earlier frame).
SonarPlane movedPlane(const SonarPlane& plane, const Pose2& motion);
/// The planes of `now` that one of `before` (already moved into the same frame) repeats.
std::vector<SonarPlane> repeatedPlanes(const std::vector<SonarPlane>& now, const std::vector<SonarPlane>& before,
                                       const SonarPlaneFillOptions& options);
/// Whether fewer than options.max_return_fraction of the scan's beams return within `max_range`.
bool laserSeesLittle(const LaserScan& scan, double max_range, const SonarPlaneFillOptions& options);
/// Fills the scan's beams that meet a plane (see above); returns how many readings changed.
size_t fillFromSonarPlanes(LaserScan& scan, const std::vector<SonarPlane>& planes, const SonarPlaneFillOptions& options);

}  // namespace polarslam
