#pragma once
// Duke DP-SLAM log reader (data README, duke-loop5/loop5.log), plain or gzip:
//   Odometry x y theta     the robot's absolute odometry pose (m, m, rad): in loop5.log x and y
//                          stay put while theta sweeps during the first turns on the spot, so the
//                          fields are a pose, not increments
//   Laser n r1..rn         n ranges in m; 181 beams = 1° over −90°..+90° (the CARMEN grid)
// The log has no timestamps: each Odometry+Laser pair gets the next tick of a nominal period
// (DukeOptions::period, 0.2 s: in loop5.log that makes the median step 0.57 m/s and the largest
// 1.2 m/s, a Pioneer's pace, and a 5 Hz SICK rate). Time starts at 0.
// Ranges at or above 8.18 m are "no return" (the SICK in its 8 m mode writes 8.183..8.191; the
// longest real return is 8.178 m) and stay beyond range_max, as in the CARMEN reader.
// Malformed lines are counted with their line numbers and skipped; they are never fatal, but
// still use up their time slot so that the following pairs keep their nominal times.
#include <functional>
#include <istream>
#include <string>

#include "io/carmen.hpp"

namespace polarslam {

struct DukeOptions {
  /// Seconds between consecutive Odometry+Laser pairs (the log records no time).
  double period = 0.2;
  /// Ranges at or above this (m) are "no return"; it becomes range_max.
  double no_return_range = 8.18;
  /// Laser mount in the robot frame (the log does not say; none by default).
  Pose2 laser_pose;
  std::function<void(double)> progress;
};

CarmenLog readDukeLog(std::istream& in, const DukeOptions& options = {});
/// Reads a Duke log file, gzip-compressed or not; throws std::runtime_error naming the file when
/// it cannot be read.
CarmenLog readDukeLogFile(const std::string& path, const DukeOptions& options = {});

}  // namespace polarslam
