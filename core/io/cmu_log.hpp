#pragma once
// CMU Wean Hall log reader (data README, cmu-wean-hall/instruct.txt), plain or gzip:
//   O x y theta ts                         odometry: cm, cm, rad, seconds since the start
//   L x y theta xl yl thetal r1..r180 ts   laser: robot pose and laser pose (both interpolated
//                                          odometry, cm/rad), 180 ranges in cm, seconds
// Ranges start at the robot's right and go counter-clockwise over 180°: the CARMEN 180-beam grid,
// 1° from −90° to +89°. 8183 cm (81.83 m) means "no return" and stays beyond range_max, as in the
// CARMEN reader. O lines become odometry readings; each L line gives an odometry reading from its
// robot pose (odometry interpolated to the scan's own time: the best prior for that scan) followed
// by the scan, like a CARMEN FLASER line. Timestamps are the log's seconds since the start in µs.
// Malformed lines are counted with their line numbers and skipped; they are never fatal.
#include <functional>
#include <istream>
#include <string>

#include "io/carmen.hpp"

namespace polarslam {

struct CmuOptions {
  /// Ranges at or above this (m) are "no return" (the logs write 8183 cm); it becomes range_max.
  double no_return_range = 80.0;
  /// Laser mount in the robot frame: 25 cm ahead of the centre (instruct.txt; the L lines' laser
  /// poses sit 25 cm ahead of their robot poses).
  Pose2 laser_pose{0.25, 0.0, 0.0};
  /// Also emit the L lines' robot poses as odometry readings, just before each scan.
  bool odometry_from_laser_lines = true;
  std::function<void(double)> progress;
};

CarmenLog readCmuLog(std::istream& in, const CmuOptions& options = {});
/// Reads a CMU log file, gzip-compressed or not; throws std::runtime_error naming the file when it
/// cannot be read.
CarmenLog readCmuLogFile(const std::string& path, const CmuOptions& options = {});

}  // namespace polarslam
