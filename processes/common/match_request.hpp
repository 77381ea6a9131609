#pragma once
// One line of `polarslam match --pairs`: {"ref": SCAN, "cur": SCAN, "guess": [x, y, theta]} with
// SCAN = {"angle_min", "angle_increment", "range_max", "ranges": [...]} (null range = no return).
// Format: core/scanmatch/README.md.
#include <string>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"

namespace polarslam {

struct MatchRequest {
  LaserScan ref, cur;
  Pose2 guess;  ///< zero motion when the line has no "guess"
};

/// Parses and validates one JSON line; returns "" or why it is bad input ("bad input: ...").
std::string parseMatchRequest(const std::string& text, MatchRequest& request);

}  // namespace polarslam
