#include "io/carmen.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "io/text_fields.hpp"

namespace polarslam {
namespace {

bool parseDouble(std::string_view text, double& value) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

bool parseCount(std::string_view text, int64_t& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

/// Why a line is malformed; thrown inside the line parser and caught per line.
struct Malformed {
  std::string reason;
};

std::string quoted(std::string_view field) {
  constexpr size_t kMaxShown = 24;
  std::string s(field.substr(0, kMaxShown));
  if (field.size() > kMaxShown) s += "...";
  return "'" + s + "'";
}

/// Reads fields of one line in order, naming the line kind and field in every complaint.
class FieldCursor {
 public:
  FieldCursor(std::string_view kind, const std::vector<std::string_view>& fields)
      : kind_(kind), fields_(fields) {}

  double number(const char* what) {
    const std::string_view f = take(what);
    double v = 0.0;
    if (!parseDouble(f, v)) fail(std::string(what) + " " + quoted(f) + " is not a number");
    return v;
  }
  double finite(const char* what) {
    const double v = number(what);
    if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
    return v;
  }
  /// A range reading: any number (NaN/inf become "no return" downstream).
  float range(size_t index) {
    const std::string_view f = take("range");
    double v = 0.0;
    if (!parseDouble(f, v)) fail("range " + std::to_string(index) + " " + quoted(f) + " is not a number");
    return static_cast<float>(v);
  }
  int64_t count(const char* what, int64_t max) {
    const std::string_view f = take(what);
    int64_t n = 0;
    if (!parseCount(f, n)) fail(std::string(what) + " " + quoted(f) + " is not an integer");
    if (n < 0 || n > max) fail(std::string(what) + " " + std::to_string(n) + " out of range [0, " + std::to_string(max) + "]");
    return n;
  }
  int64_t timestamp(const char* what) {
    const std::string_view f = take(what);
    int64_t utime = 0;
    if (!parseSecondsToUtime(f, utime)) fail(std::string(what) + " " + quoted(f) + " is not a time in seconds");
    return utime;
  }
  void skip(size_t n = 1) {
    if (next_ + n > fields_.size()) fail("line ends early");
    next_ += n;
  }
  /// Checks the total field count once the variable-length parts are known.
  void expectTotal(size_t total, const char* formula) {
    if (fields_.size() != total)
      fail("expected " + std::string(formula) + " = " + std::to_string(total) + " fields, got " +
           std::to_string(fields_.size()));
  }
  [[noreturn]] void fail(const std::string& why) const { throw Malformed{std::string(kind_) + ": " + why}; }

 private:
  std::string_view take(const char* what) {
    if (next_ >= fields_.size()) fail(std::string("line ends before ") + what);
    return fields_[next_++];
  }
  std::string_view kind_;
  const std::vector<std::string_view>& fields_;
  size_t next_ = 1;  // field 0 is the message name
};

void checkScan(const LaserScan& scan, FieldCursor& cursor) {
  const std::string why = validateScan(scan);
  if (!why.empty()) cursor.fail(why);
}

struct LineParser {
  const CarmenOptions& options;

  // FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
  std::pair<LaserScan, OdometryReading> flaser(const std::vector<std::string_view>& fields, bool& usual) {
    FieldCursor in("FLASER", fields);
    const auto n = static_cast<size_t>(in.count("beam count", static_cast<int64_t>(kMaxLaserBeams)));
    in.expectTotal(n + 11, "n + 11");
    LaserScan scan;
    scan.ranges.resize(n);
    for (size_t i = 0; i < n; ++i) scan.ranges[i] = in.range(i);
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
    in.finite("fov");
    scan.angle_increment = in.finite("angular_res");
    const double max_range = in.finite("max_range");
    in.skip(2);  // accuracy, remission mode
    const auto n = static_cast<size_t>(in.count("beam count", static_cast<int64_t>(kMaxLaserBeams)));
    if (fields.size() < n + 10) in.fail("line ends inside the ranges");
    scan.ranges.resize(n);
    for (size_t i = 0; i < n; ++i) scan.ranges[i] = in.range(i);
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

std::streamoff streamSize(std::istream& in) {
  const auto start = in.tellg();
  if (start < 0) return -1;
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(start);
  return end < 0 ? -1 : static_cast<std::streamoff>(end - start);
}

void recordMalformed(CarmenLog& log, int64_t line, std::string reason) {
  ++log.malformed_count;
  if (log.malformed.size() < CarmenLog::kMaxReportedIssues) log.malformed.push_back({line, std::move(reason)});
}

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

void numberSequences(CarmenLog& log) {
  int64_t laser_seq = 0, odometry_seq = 0;
  for (CarmenEvent& e : log.events) {
    if (auto* scan = std::get_if<LaserScan>(&e.data)) scan->seq = laser_seq++;
    else std::get<OdometryReading>(e.data).seq = odometry_seq++;
  }
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
  if (text.empty()) return false;
  if (text.find_first_of("eEnN") != std::string_view::npos) {  // exponent form (or nan/inf)
    double seconds = 0.0;
    if (!parseDouble(text, seconds) || !std::isfinite(seconds) || std::abs(seconds) > 9e12) return false;
    utime = std::llround(seconds * 1e6);
    return true;
  }
  bool negative = false;
  if (text.front() == '-' || text.front() == '+') {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  const size_t dot = text.find('.');
  const std::string_view whole = text.substr(0, dot);
  const std::string_view fraction = dot == std::string_view::npos ? std::string_view{} : text.substr(dot + 1);
  if (whole.empty() && fraction.empty()) return false;
  if (whole.size() > 12) return false;  // beyond ~31 700 years: not a timestamp
  int64_t us = 0;
  for (char c : whole) {
    if (c < '0' || c > '9') return false;
    us = us * 10 + (c - '0');
  }
  us *= 1'000'000;
  int64_t scale = 100'000;
  bool round_up = false;
  for (size_t i = 0; i < fraction.size(); ++i) {
    const char c = fraction[i];
    if (c < '0' || c > '9') return false;
    if (i < 6) {
      us += (c - '0') * scale;
      scale /= 10;
    } else if (i == 6) {
      round_up = c >= '5';
    }
  }
  if (round_up) ++us;
  utime = negative ? -us : us;
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
  const std::streamoff total = options.progress ? streamSize(in) : -1;
  std::streamoff consumed = 0;
  int64_t last_laser_utime = std::numeric_limits<int64_t>::min();
  std::string line;
  while (std::getline(in, line)) {
    ++log.lines;
    consumed += static_cast<std::streamoff>(line.size() + 1);
    if (total > 0 && log.lines % 256 == 0) options.progress(static_cast<double>(consumed) / static_cast<double>(total));
    const std::vector<std::string_view> fields = splitFields(line);
    if (fields.empty() || fields.front().front() == '#') {
      ++log.comment_lines;
      continue;
    }
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
    try {
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
    } catch (const Malformed& m) {
      recordMalformed(log, log.lines, m.reason);
    }
  }
  settleOdometrySource(log, from_robotlaser);
  numberSequences(log);
  if (options.progress) options.progress(1.0);
  return log;
}

CarmenLog readCarmenLogFile(const std::string& path, const CarmenOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open CARMEN log '" + path + "'");
  return readCarmenLog(in, options);
}

}  // namespace polarslam
