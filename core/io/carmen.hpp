#pragma once
// CARMEN log reader (docs/algorithms.md §20.2–§20.3, data README): FLASER, ROBOTLASER1 and ODOM lines
// become LaserScan and OdometryReading events, in file order (never sorted: real logs step back
// in time and relations refer to the exact stamps). Timestamps are the lines' ipc_timestamp in µs.
// Malformed lines are counted with their line numbers and skipped; they are never fatal.
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "geometry/pose2.hpp"
#include "laser/laser_scan.hpp"
#include "odometry/odometry_reading.hpp"

namespace polarslam {

struct CarmenOptions {
  /// Ranges at or above this are "no return" (SICK logs write 81.83 or 81.91 m); it becomes the
  /// scans' range_max. ROBOTLASER1 lines use their own max_range when it is smaller.
  double no_return_range = 80.0;
  /// FLASER lines do not say where the laser sits on the robot; give the mount here
  /// (e.g. 0.78 m ahead for the Málaga log). ROBOTLASER1 lines carry their own.
  Pose2 flaser_laser_pose;
  /// Called now and then with the fraction of the input read.
  std::function<void(double)> progress;
};

struct CarmenEvent {
  int64_t line = 0;  ///< 1-based line number in the file
  std::variant<LaserScan, OdometryReading> data;

  bool isLaser() const { return std::holds_alternative<LaserScan>(data); }
  const LaserScan& laser() const { return std::get<LaserScan>(data); }
  const OdometryReading& odometry() const { return std::get<OdometryReading>(data); }
  int64_t utime() const { return isLaser() ? laser().utime : odometry().utime; }
};

struct CarmenIssue {
  int64_t line = 0;
  std::string reason;
};

/// A range log read into memory: laser scans and odometry in file order. CARMEN's type, shared by
/// the readers of the other formats (io/range_log.hpp names it RangeLog); the per-kind counters
/// below that name CARMEN messages stay zero for them, `line_kinds` counts their line kinds.
struct CarmenLog {
  std::string format = "carmen";   ///< carmen, cmu, duke or mines
  std::vector<CarmenEvent> events;  ///< in file order
  int64_t lines = 0;
  std::map<std::string, int64_t> line_kinds;  ///< lines read, by kind (non-CARMEN formats)
  std::vector<std::string> notes;  ///< what the reader assumed or derived, for the user
  int64_t flaser_lines = 0, robotlaser_lines = 0, odom_lines = 0;
  int64_t comment_lines = 0;  ///< blank lines and '#' comments
  std::map<std::string, int64_t> skipped_kinds;  ///< other message types (PARAM, SYNC, OLD...), by name
  int64_t malformed_count = 0;
  std::vector<CarmenIssue> malformed;  ///< the first kMaxReportedIssues malformed lines
  int64_t laser_time_reversals = 0;    ///< laser stamps earlier than the previous one (kept as they are)
  int64_t unusual_beam_counts = 0;     ///< FLASER lines whose beam count is not 180/181/360/361 (180° assumed)
  /// True when odometry was taken from ROBOTLASER1 robot poses because the log has no ODOM lines.
  bool odometry_from_robotlaser = false;

  static constexpr size_t kMaxReportedIssues = 1000;
  int64_t laserCount() const;
  int64_t odometryCount() const;
};

/// Reads a CARMEN log from a stream.
CarmenLog readCarmenLog(std::istream& in, const CarmenOptions& options = {});
/// Reads a CARMEN log file, plain or gzip; throws std::runtime_error naming the file when it cannot
/// be read.
CarmenLog readCarmenLogFile(const std::string& path, const CarmenOptions& options = {});

/// Bearing grid of a FLASER line, which records only the beam count (§20.3): 180 beams = 1° from
/// −90°, 181 = 1° over −90°..+90°, 360/361 = 0.5° from −90°; any other count is spread over 180°.
struct FlaserGeometry {
  double angle_min = 0.0, angle_increment = 0.0;
  bool usual = true;  ///< false when the beam count was not one of 180/181/360/361
};
FlaserGeometry flaserGeometry(size_t beams);

/// Decimal seconds ("1134864645.90321") to µs, digit by digit so that no precision is lost.
/// Returns false when the text is not a number.
bool parseSecondsToUtime(std::string_view text, int64_t& utime);

}  // namespace polarslam
