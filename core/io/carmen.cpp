#include "io/carmen.hpp"

#include <algorithm>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>

#include "io/log_lines.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {

struct LineParser {
  const CarmenOptions& options;

  // FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
  std::pair<LaserScan, OdometryReading> flaser(const std::vector<std::string_view>& fields, bool& usual) {
    FieldCursor in("FLASER", fields);
    const auto n = static_cast<size_t>(in.count("beam count", static_cast<int64_t>(kMaxLaserBeams)));
    in.expectTotal(n + 11, "n + 11");
    LaserScan scan;
    scan.ranges = in.ranges(n);
    in.skip(3);  // the laser pose triple: corrected or not depending on the log; the odometry is next
    OdometryReading odo;
    odo.pose.x = in.finite("odom_x");
    odo.pose.y = in.finite("odom_y");
    odo.pose.theta = wrapAngle(in.finite("odom_theta"));
    const int64_t utime = in.timestamp("ipc_timestamp");
    const FlaserGeometry geometry = flaserGeometry(n);
    usual = geometry.usual;
    scan.utime = odo.utime = utime;
    scan.angle_min = geometry.angle_min;
    scan.angle_increment = geometry.angle_increment;
    scan.range_max = options.no_return_range;
    scan.laser_pose = options.flaser_laser_pose;
    checkScan(scan, in);
    return {std::move(scan), odo};
  }

  // ROBOTLASER1 type start_angle fov res max_range accuracy remission_mode n r1..rn n_rem rem..
  //   laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv fsd ssd turn_axis ipc host logger
  std::pair<LaserScan, OdometryReading> robotlaser(const std::vector<std::string_view>& fields) {
    FieldCursor in("ROBOTLASER1", fields);
    in.skip();  // laser type
    LaserScan scan;
    scan.angle_min = in.finite("start_angle");
    const double fov = in.finite("fov");
    if (!(fov > 0.0 && fov <= 2.0 * std::numbers::pi + 1e-6)) in.fail("fov must be in (0, 2 pi]");
    scan.angle_increment = in.finite("angular_res");
    const double max_range = in.finite("max_range");
    in.skip(2);  // accuracy, remission mode
    const auto n = static_cast<size_t>(in.count("beam count", static_cast<int64_t>(kMaxLaserBeams)));
    if (fields.size() < n + 10) in.fail("line ends inside the ranges");
    scan.ranges = in.ranges(n);
    const auto n_rem = static_cast<size_t>(in.count("remission count", static_cast<int64_t>(kMaxLaserBeams)));
    in.expectTotal(24 + n + n_rem, "24 + n + n_remissions");
    in.skip(n_rem);
    const Pose2 laser{in.finite("laser_x"), in.finite("laser_y"), wrapAngle(in.finite("laser_theta"))};
    OdometryReading odo;
    odo.pose = Pose2{in.finite("robot_x"), in.finite("robot_y"), wrapAngle(in.finite("robot_theta"))};
    odo.v = in.finite("tv");
    odo.omega = in.finite("rv");
    in.skip(3);  // safety distances, turn axis
    scan.utime = odo.utime = in.timestamp("ipc_timestamp");
    scan.range_max = max_range > 0.0 ? std::min(max_range, options.no_return_range) : options.no_return_range;
    scan.laser_pose = between(odo.pose, laser);
    checkScan(scan, in);
    return {std::move(scan), odo};
  }

  // ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
  OdometryReading odom(const std::vector<std::string_view>& fields) {
    FieldCursor in("ODOM", fields);
    in.expectTotal(10, "10");
    OdometryReading odo;
    odo.pose = Pose2{in.finite("x"), in.finite("y"), wrapAngle(in.finite("theta"))};
    odo.v = in.finite("tv");
    odo.omega = in.finite("rv");
    in.finite("accel");
    odo.utime = in.timestamp("ipc_timestamp");
    return odo;
  }
};

/// ROBOTLASER1 robot poses stand in for odometry only when the log has no ODOM lines.
void settleOdometrySource(CarmenLog& log, std::vector<bool>& from_robotlaser) {
  if (log.robotlaser_lines == 0) return;
  if (log.odom_lines == 0) {
    log.odometry_from_robotlaser = true;
    return;
  }
  std::vector<CarmenEvent> kept;
  kept.reserve(log.events.size());
  for (size_t i = 0; i < log.events.size(); ++i)
    if (!from_robotlaser[i]) kept.push_back(std::move(log.events[i]));
  log.events = std::move(kept);
}

}  // namespace

FlaserGeometry flaserGeometry(size_t beams) {
  const double half_pi = std::numbers::pi / 2.0;
  switch (beams) {
    case 180: case 181: return {-half_pi, deg2rad(1.0), true};
    case 360: case 361: return {-half_pi, deg2rad(0.5), true};
    default: return {-half_pi, beams > 1 ? std::numbers::pi / static_cast<double>(beams - 1) : deg2rad(1.0), false};
  }
}

bool parseSecondsToUtime(std::string_view text, int64_t& utime) {
  const std::optional<int64_t> us = parseSecondsAsUtime(text);
  if (!us) return false;
  utime = *us;
  return true;
}

int64_t CarmenLog::laserCount() const {
  return std::count_if(events.begin(), events.end(), [](const CarmenEvent& e) { return e.isLaser(); });
}
int64_t CarmenLog::odometryCount() const { return static_cast<int64_t>(events.size()) - laserCount(); }

CarmenLog readCarmenLog(std::istream& in, const CarmenOptions& options) {
  CarmenLog log;
  LineParser parser{options};
  std::vector<bool> from_robotlaser;  // parallel to log.events
  int64_t last_laser_utime = std::numeric_limits<int64_t>::min();
  forEachLogLine(in, log, options.progress, [&](const std::vector<std::string_view>& fields) {
    const std::string_view kind = fields.front();
    auto addLaser = [&](LaserScan&& scan) {
      if (scan.utime < last_laser_utime) ++log.laser_time_reversals;
      last_laser_utime = scan.utime;
      log.events.push_back({log.lines, std::move(scan)});
      from_robotlaser.push_back(false);
    };
    auto addOdometry = [&](const OdometryReading& odo, bool robotlaser) {
      log.events.push_back({log.lines, odo});
      from_robotlaser.push_back(robotlaser);
    };
    if (kind == "FLASER") {
      bool usual = true;
      auto [scan, odo] = parser.flaser(fields, usual);
      ++log.flaser_lines;
      if (!usual) ++log.unusual_beam_counts;
      addOdometry(odo, false);  // odometry first: a consumer then has the prior when the scan arrives
      addLaser(std::move(scan));
    } else if (kind == "ROBOTLASER1") {
      auto [scan, odo] = parser.robotlaser(fields);
      ++log.robotlaser_lines;
      addOdometry(odo, true);
      addLaser(std::move(scan));
    } else if (kind == "ODOM") {
      addOdometry(parser.odom(fields), false);
      ++log.odom_lines;
    } else {
      ++log.skipped_kinds[std::string(kind.substr(0, 32))];
    }
  });
  settleOdometrySource(log, from_robotlaser);
  numberSequences(log);
  return log;
}

CarmenLog readCarmenLogFile(const std::string& path, const CarmenOptions& options) {
  std::istringstream in(readMaybeGzipFile(path, "CARMEN log"));
  return readCarmenLog(in, options);
}

}  // namespace polarslam
