#include "io/mines_log.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include "io/log_lines.hpp"

namespace polarslam {

CarmenLog readMinesLog(std::istream& in, const MinesOptions& options) {
  CarmenLog log;
  log.format = "mines";
  const size_t ranges_end = options.first_range_column + options.beams;
  const double rad_per_count = 2.0 * std::numbers::pi / options.counts_per_turn;
  const double angle_min = -0.5 * static_cast<double>(options.beams - 1) * options.angle_increment;
  bool have_previous = false;
  int64_t previous_left = 0, previous_right = 0;
  Pose2 pose;
  int64_t last_laser_utime = std::numeric_limits<int64_t>::min();
  forEachLogLine(in, log, options.progress, [&](const std::vector<std::string_view>& fields) {
    FieldCursor c("Mines line", fields, 0);
    if (fields.size() != ranges_end && fields.size() != ranges_end + 1)
      c.fail("expected " + std::to_string(ranges_end) + " or " + std::to_string(ranges_end + 1) + " columns, got " +
             std::to_string(fields.size()));
    const int64_t utime = c.integer("timestamp (us)", 0, std::numeric_limits<int64_t>::max());
    c.skip();
    const int64_t left = c.integer("left wheel count", std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max());
    const int64_t right = c.integer("right wheel count", std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max());
    c.skip(options.first_range_column - 4);
    LaserScan scan;
    scan.ranges.resize(options.beams);
    for (size_t i = 0; i < options.beams; ++i) {
      const double r = c.range(i) * 1e-3;
      scan.ranges[i] = r < options.min_valid_range ? std::numeric_limits<float>::infinity() : static_cast<float>(r);
    }
    scan.utime = utime;
    scan.angle_min = angle_min;
    scan.angle_increment = options.angle_increment;
    scan.range_max = options.range_max;
    scan.laser_pose = options.laser_pose;
    checkScan(scan, c);

    if (have_previous) {
      // Differences modulo 2^32: a wrapping 32-bit counter still gives the small true step.
      const auto step = [](int64_t now, int64_t before) {
        return static_cast<double>(static_cast<int32_t>(static_cast<uint32_t>(now) - static_cast<uint32_t>(before)));
      };
      const double dl = step(left, previous_left) * rad_per_count * options.wheel_radius;
      const double dr = step(right, previous_right) * rad_per_count * options.wheel_radius;
      const double ds = 0.5 * (dl + dr);
      const double dtheta = (dr - dl) / (2.0 * options.half_axle);
      const double mid = pose.theta + 0.5 * dtheta;
      pose = Pose2{pose.x + ds * std::cos(mid), pose.y + ds * std::sin(mid), wrapAngle(pose.theta + dtheta)};
    }
    have_previous = true;
    previous_left = left;
    previous_right = right;
    OdometryReading odo;
    odo.utime = utime;
    odo.pose = pose;
    log.events.push_back({log.lines, odo});
    if (scan.utime < last_laser_utime) ++log.laser_time_reversals;
    last_laser_utime = scan.utime;
    log.events.push_back({log.lines, std::move(scan)});
    ++log.line_kinds["scan"];
  });
  numberSequences(log);
  return log;
}

CarmenLog readMinesLogFile(const std::string& path, const MinesOptions& options) {
  std::istringstream in(readMaybeGzipFile(path, "Mines log"));
  return readMinesLog(in, options);
}

}  // namespace polarslam
