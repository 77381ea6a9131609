#pragma once
// Mines ParisTech (CoreSLAM/BreezySLAM) log reader (data README, mines-paristech/exp*.dat), plain
// or gzip. One line per scan, whitespace-separated numbers, columns counted from 0:
//   0        timestamp, µs (kept as it is)
//   2, 3     left and right wheel encoder counts, cumulative (integers)
//   4..23    other sensors, unused (column 7 holds decimals such as 167.2)
//   24..705  682 ranges, mm, of a Hokuyo URG-04LX over its 240° field of view
//   706      a trailing column that is not a range (BreezySLAM drops it too); lines of 706
//            columns are accepted as well
// Ranges: the URG's step is 360°/1024, so beam i lies at (i − 340.5)·360°/1024 (−119.7°..+119.7°),
// counter-clockwise. 0 means no return and 1..19 mm are URG error codes: both become +inf.
// Odometry: the wheel counts are integrated as a differential drive (wheel radius 77 mm, half axle
// 165 mm) with 2000 counts per wheel turn. The README's "degrees = ticks·180/2000" comes from
// BreezySLAM, whose motion formulas omit the usual 1/2 (ds = r(φl+φr), dθ = r(φr−φl)/h): the two
// together are exactly the standard formulas with 2000 counts per turn. Count differences are
// taken modulo 2^32, so a 32-bit counter may wrap (exp1/exp2 never do). The pose starts at 0.
// Malformed lines are counted with their line numbers and skipped; they are never fatal.
#include <functional>
#include <istream>
#include <numbers>
#include <string>

#include "io/carmen.hpp"

namespace polarslam {

struct MinesOptions {
  double wheel_radius = 0.077;        ///< m
  double half_axle = 0.165;           ///< m, half the distance between the wheels
  double counts_per_turn = 2000.0;    ///< encoder counts per wheel revolution
  Pose2 laser_pose{0.07, 0.0, 0.0};   ///< laser mount in the robot frame (data README: 70 mm ahead)
  size_t beams = 682;
  size_t first_range_column = 24;
  double angle_increment = 2.0 * std::numbers::pi / 1024.0;  ///< rad, the URG-04LX step
  /// Ranges below this (m) are no return (0) or URG error codes (1..19 mm): they become +inf.
  double min_valid_range = 0.02;
  /// range_max of the scans (the URG-04LX reports up to about 5.6 m).
  double range_max = 5.6;
  std::function<void(double)> progress;
};

CarmenLog readMinesLog(std::istream& in, const MinesOptions& options = {});
/// Reads a Mines log file, gzip-compressed or not; throws std::runtime_error naming the file when
/// it cannot be read.
CarmenLog readMinesLogFile(const std::string& path, const MinesOptions& options = {});

}  // namespace polarslam
