#include "io/duke_log.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "io/log_lines.hpp"

namespace polarslam {

CarmenLog readDukeLog(std::istream& in, const DukeOptions& options) {
  if (!(options.period > 0.0) || !std::isfinite(options.period))
    throw std::invalid_argument("Duke log period must be positive, got " + std::to_string(options.period));
  CarmenLog log;
  log.format = "duke";
  const auto period_us = static_cast<int64_t>(std::llround(options.period * 1e6));
  // Time slots: an Odometry line opens a new pair unless the current one has nothing yet; a Laser
  // line joins the current pair unless that already has a laser.
  int64_t slot = -1;
  bool slot_has_odometry = false, slot_has_laser = false;
  auto openSlot = [&] {
    ++slot;
    slot_has_odometry = slot_has_laser = false;
  };
  forEachLogLine(in, log, options.progress, [&](const std::vector<std::string_view>& fields) {
    const std::string_view kind = fields.front();
    if (kind == "Odometry") {
      if (slot < 0 || slot_has_odometry || slot_has_laser) openSlot();
      slot_has_odometry = true;
      FieldCursor c("Odometry", fields);
      c.expectTotal(4, "4");
      OdometryReading odo;
      odo.pose.x = c.finite("x");
      odo.pose.y = c.finite("y");
      odo.pose.theta = wrapAngle(c.finite("theta"));
      odo.utime = slot * period_us;
      log.events.push_back({log.lines, odo});
      ++log.line_kinds["Odometry"];
    } else if (kind == "Laser") {
      if (slot < 0 || slot_has_laser) openSlot();
      slot_has_laser = true;
      FieldCursor c("Laser", fields);
      const auto n = static_cast<size_t>(c.count("beam count", static_cast<int64_t>(kMaxLaserBeams)));
      c.expectTotal(n + 2, "n + 2");
      LaserScan scan;
      scan.ranges = c.ranges(n);
      const FlaserGeometry geometry = flaserGeometry(n);
      if (!geometry.usual) ++log.unusual_beam_counts;
      scan.utime = slot * period_us;
      scan.angle_min = geometry.angle_min;
      scan.angle_increment = geometry.angle_increment;
      scan.range_max = options.no_return_range;
      scan.laser_pose = options.laser_pose;
      checkScan(scan, c);
      log.events.push_back({log.lines, std::move(scan)});
      ++log.line_kinds["Laser"];
    } else {
      ++log.skipped_kinds[std::string(kind.substr(0, 32))];
    }
  });
  numberSequences(log);
  if (slot >= 0) {
    std::ostringstream note;
    note << "no timestamps in the log: " << slot + 1 << " Odometry+Laser pairs stamped every " << options.period << " s";
    log.notes.push_back(note.str());
  }
  return log;
}

CarmenLog readDukeLogFile(const std::string& path, const DukeOptions& options) {
  std::istringstream in(readMaybeGzipFile(path, "Duke log"));
  return readDukeLog(in, options);
}

}  // namespace polarslam
