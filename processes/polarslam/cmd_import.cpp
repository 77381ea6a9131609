// polarslam import IN -o OUT.lcmlog [--format auto|carmen|cmu|duke|mines|rosbag]: a range log
// (CARMEN, CMU Wean Hall, Duke DP-SLAM, Mines ParisTech; plain or gzip) or a ROS 1 bag
// (sensor_msgs/LaserScan, nav_msgs/Odometry, tf) as an LCM log of LASER and ODOMETRY messages,
// keeping the log's timestamps and their order.
// polarslam import-carmen IN.clf -o OUT.lcmlog: the same with the format fixed to CARMEN.
#include <algorithm>
#include <iostream>
#include <sstream>

#include "command_registry.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"
#include "io/log_lines.hpp"
#include "io/range_log.hpp"
#ifdef POLARSLAM_HAVE_ROSBAG
#include "rosbag/ros_bag_log.hpp"
#endif

namespace polarslam {
namespace {

struct ImportOptions {
  std::string command;  ///< "import" or "import-carmen", for messages
  std::string in, out;
  std::string format = "auto";
  std::string laser_channel = "LASER", odometry_channel = "ODOMETRY";
  std::string laser_topic, odometry_topic;  ///< ROS bags: "" = the bag's only one
  double no_return_range = 0.0;    ///< 0: the format's default
  std::vector<double> laser_pose;  ///< empty: the format's default
  double period = DukeOptions{}.period;
  size_t show_malformed = 5;
};

std::string summary(const RangeLog& log) {
  std::ostringstream s;
  s << log.lines << " lines: ";
  if (log.format == "carmen") {
    s << log.flaser_lines << " FLASER, " << log.robotlaser_lines << " ROBOTLASER1, " << log.odom_lines << " ODOM";
  } else {
    bool first = true;
    for (const auto& [kind, count] : log.line_kinds) {
      s << (first ? "" : ", ") << count << " " << kind;
      first = false;
    }
    if (first) s << "no " << log.format << " lines";
  }
  s << ", " << log.comment_lines << " comments/blank";
  // A file of another format can hold thousands of distinct first words: name a few.
  constexpr size_t kMaxKindsShown = 5;
  size_t shown = 0;
  int64_t other_lines = 0;
  for (const auto& [kind, count] : log.skipped_kinds) {
    if (shown++ < kMaxKindsShown) s << ", " << count << " " << kind << " (skipped)";
    else other_lines += count;
  }
  if (shown > kMaxKindsShown)
    s << ", " << other_lines << " lines of " << shown - kMaxKindsShown << " other unknown kinds (skipped)";
  s << ", " << log.malformed_count << " malformed";
  return s.str();
}

RangeLogOptions readerOptions(const ImportOptions& o) {
  RangeLogOptions options;
  if (o.no_return_range > 0.0) {
    options.carmen.no_return_range = options.cmu.no_return_range = options.duke.no_return_range = o.no_return_range;
    options.mines.range_max = o.no_return_range;
  }
  if (!o.laser_pose.empty()) {
    const Pose2 mount{o.laser_pose[0], o.laser_pose[1], o.laser_pose[2]};
    options.carmen.flaser_laser_pose = options.cmu.laser_pose = options.duke.laser_pose = options.mines.laser_pose = mount;
  }
  options.duke.period = o.period;
  return options;
}

/// The input as a range log; `format` receives the format's name.
RangeLog readInput(const ImportOptions& o, ProgressBar& progress, std::string& format) {
#ifdef POLARSLAM_HAVE_ROSBAG
  if (o.format == "rosbag" || (o.format == "auto" && looksLikeRosBag(o.in))) {
    format = "rosbag";
    return readRosBag(o.in, {o.laser_topic, o.odometry_topic});
  }
#else
  if (o.format == "rosbag") throw std::runtime_error("this build has no ROS 1 bag support (librosbag-dev)");
#endif
  const std::optional<RangeLogFormat> requested = parseRangeLogFormat(o.format);
  if (!requested) throw std::runtime_error("unknown format '" + o.format + "' (auto, carmen, cmu, duke, mines, rosbag)");
  const std::string text = readMaybeGzipFile(o.in, "range log");
  const RangeLogFormat detected = *requested == RangeLogFormat::Auto ? detectRangeLogFormat(text, o.in) : *requested;
  format = rangeLogFormatName(detected);
  RangeLogOptions options = readerOptions(o);
  const auto report = [&](double f) { progress.update(0.8 * f); };
  options.carmen.progress = options.cmu.progress = options.duke.progress = options.mines.progress = report;
  return readRangeLogText(text, o.in, detected, options);
}

void importRangeLog(const ImportOptions& o) {
  ProgressBar progress(o.command);
  std::string format;
  const RangeLog log = readInput(o, progress, format);
  if (log.laserCount() == 0) {
    progress.finish();
    std::string why = "'" + o.in + "' holds no usable laser line of the " + format +
                      " format (" + summary(log) + ")";
    if (!log.malformed.empty()) why += "; first problem: " + o.in + ":" + std::to_string(log.malformed[0].line) + ": " + log.malformed[0].reason;
    throw std::runtime_error(why);
  }
  LcmLogWriter writer(o.out);
  int64_t lasers = 0, odometries = 0;
  for (size_t k = 0; k < log.events.size(); ++k) {
    const RangeLogEvent& e = log.events[k];
    // Each event is logged at its message time, in file order, even where time steps back.
    if (e.isLaser()) {
      writer.write(o.laser_channel, e.laser().utime, toLcm(e.laser()));
      ++lasers;
    } else {
      writer.write(o.odometry_channel, e.odometry().utime, toLcm(e.odometry()));
      ++odometries;
    }
    if (k % 512 == 0) progress.update(0.8 + 0.2 * static_cast<double>(k) / static_cast<double>(log.events.size()));
  }
  writer.close();
  progress.finish();

  const std::string& c = o.command;
  std::cout << c << ": " << format << " log, " << summary(log) << "\n";
  std::cout << c << ": wrote " << lasers << " " << o.laser_channel << " and " << odometries << " "
            << o.odometry_channel << " messages to " << o.out << "\n";
  for (const std::string& note : log.notes) std::cout << c << ": " << note << "\n";
  if (log.odometry_from_robotlaser)
    std::cout << c << ": no ODOM lines: odometry taken from the ROBOTLASER1 robot poses\n";
  if (log.laser_time_reversals > 0)
    std::cout << c << ": " << log.laser_time_reversals
              << " laser timestamps step back in time (kept in file order, as relations expect)\n";
  if (log.unusual_beam_counts > 0)
    std::cout << c << ": " << log.unusual_beam_counts
              << " scans with a beam count other than 180/181/360/361: assumed to span 180 degrees\n";
  const size_t shown = std::min(o.show_malformed, log.malformed.size());
  for (size_t k = 0; k < shown; ++k)
    std::cout << "  " << o.in << ":" << log.malformed[k].line << ": " << log.malformed[k].reason << "\n";
  if (log.malformed_count > static_cast<int64_t>(shown))
    std::cout << "  ... and " << log.malformed_count - static_cast<int64_t>(shown) << " more malformed lines\n";
}

/// The options of `import`; `import-carmen` has the same ones, with the format fixed.
void addImportOptions(CLI::App& sub, ImportOptions& o) {
  sub.add_option("-o,--out", o.out, "LCM log to write")->required();
  sub.add_option("--laser-channel", o.laser_channel, "channel of the LASER messages written")->capture_default_str();
  sub.add_option("--odometry-channel", o.odometry_channel, "channel of the ODOMETRY messages written")
      ->capture_default_str();
  sub.add_option("--show-malformed", o.show_malformed, "how many malformed lines to list")->capture_default_str();
  sub.add_option("--no-return-range", o.no_return_range,
                 "ranges at or above this (m) are 'no return' (default per format: CARMEN and CMU 80, Duke 8.18; "
                 "for Mines, the scans' range_max, 5.6)")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--laser-pose", o.laser_pose,
                 "laser mount x y theta (m, m, rad) (default per format: CMU 0.25 0 0, Mines 0.07 0 0, none for "
                 "CARMEN FLASER and Duke; ROBOTLASER1 lines carry their own)")
      ->expected(3);
  sub.add_option("--period", o.period, "Duke logs, which have no timestamps: seconds between Odometry+Laser pairs")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--laser-topic", o.laser_topic, "ROS bags: the sensor_msgs/LaserScan topic (default: the only one)");
  sub.add_option("--odometry-topic", o.odometry_topic, "ROS bags: the nav_msgs/Odometry topic (default: the only one)");
}

void setupImport(CLI::App& sub) {
  auto o = std::make_shared<ImportOptions>();
  o->command = "import";
  sub.add_option("input", o->in,
                 "range log, plain or .gz: CARMEN .clf, CMU robotdata*.log, Duke loop5.log, Mines exp*.dat; or a ROS 1 .bag")
      ->required()->check(CLI::ExistingFile);
  sub.add_option("--format", o->format, "auto (from the content), carmen, cmu, duke, mines or rosbag")
      ->check(CLI::IsMember({"auto", "carmen", "cmu", "duke", "mines", "rosbag"}))->capture_default_str();
  addImportOptions(sub, *o);
  sub.callback([o] { importRangeLog(*o); });
}

void setupImportCarmen(CLI::App& sub) {
  auto o = std::make_shared<ImportOptions>();
  o->command = "import-carmen";
  o->format = "carmen";
  sub.add_option("input", o->in, "CARMEN log (.clf)")->required()->check(CLI::ExistingFile);
  addImportOptions(sub, *o);
  sub.callback([o] { importRangeLog(*o); });
}

RegisterCommand reg_import("import", "Convert a range log (CARMEN, CMU, Duke, Mines; plain or gzip) or a ROS 1 bag into an LCM log",
                           setupImport);
RegisterCommand reg_carmen("import-carmen", "Convert a CARMEN log (FLASER, ROBOTLASER1, ODOM) into an LCM log "
                           "(import --format carmen)", setupImportCarmen);

}  // namespace
}  // namespace polarslam
