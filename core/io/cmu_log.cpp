#include "io/cmu_log.hpp"

#include <limits>
#include <sstream>

#include "io/log_lines.hpp"

namespace polarslam {
namespace {

constexpr double kCm = 0.01;
constexpr size_t kCmuBeams = 180;

Pose2 poseInCm(FieldCursor& in, const char* x, const char* y, const char* theta) {
  const double px = in.finite(x) * kCm;
  const double py = in.finite(y) * kCm;
  return {px, py, wrapAngle(in.finite(theta))};
}

}  // namespace

CarmenLog readCmuLog(std::istream& in, const CmuOptions& options) {
  CarmenLog log;
  log.format = "cmu";
  const FlaserGeometry geometry = flaserGeometry(kCmuBeams);
  int64_t last_laser_utime = std::numeric_limits<int64_t>::min();
  forEachLogLine(in, log, options.progress, [&](const std::vector<std::string_view>& fields) {
    const std::string_view kind = fields.front();
    if (kind == "O") {
      FieldCursor c("O", fields);
      c.expectTotal(5, "5");
      OdometryReading odo;
      odo.pose = poseInCm(c, "x", "y", "theta");
      odo.utime = c.timestamp("ts");
      log.events.push_back({log.lines, odo});
      ++log.line_kinds["O"];
    } else if (kind == "L") {
      FieldCursor c("L", fields);
      c.expectTotal(kCmuBeams + 8, "180 + 8");
      OdometryReading odo;
      odo.pose = poseInCm(c, "x", "y", "theta");
      poseInCm(c, "xl", "yl", "thetal");  // the laser pose: the robot pose moved by the mount
      LaserScan scan;
      scan.ranges.resize(kCmuBeams);
      for (size_t i = 0; i < kCmuBeams; ++i) scan.ranges[i] = static_cast<float>(c.range(i) * kCm);
      scan.utime = odo.utime = c.timestamp("ts");
      scan.angle_min = geometry.angle_min;
      scan.angle_increment = geometry.angle_increment;
      scan.range_max = options.no_return_range;
      scan.laser_pose = options.laser_pose;
      checkScan(scan, c);
      if (options.odometry_from_laser_lines) log.events.push_back({log.lines, odo});
      if (scan.utime < last_laser_utime) ++log.laser_time_reversals;
      last_laser_utime = scan.utime;
      log.events.push_back({log.lines, std::move(scan)});
      ++log.line_kinds["L"];
    } else {
      ++log.skipped_kinds[std::string(kind.substr(0, 32))];
    }
  });
  numberSequences(log);
  if (options.odometry_from_laser_lines && log.line_kinds.count("L"))
    log.notes.push_back("odometry from the O lines and from the L lines' robot poses (interpolated to each scan)");
  return log;
}

CarmenLog readCmuLogFile(const std::string& path, const CmuOptions& options) {
  std::istringstream in(readMaybeGzipFile(path, "CMU log"));
  return readCmuLog(in, options);
}

}  // namespace polarslam
