// polarslam import IN -o OUT.lcmlog [--format auto|carmen|cmu|duke|mines]: a range log (CARMEN,
// CMU Wean Hall, Duke DP-SLAM, Mines ParisTech; plain or gzip) as an LCM log of LASER and
// ODOMETRY messages, keeping the log's timestamps and their order.
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

namespace polarslam {
namespace {

struct ImportOptions {
  std::string command;  ///< "import" or "import-carmen", for messages
  std::string in, out;
  std::string format = "auto";
  std::string laser_channel = "LASER", odometry_channel = "ODOMETRY";
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

void importRangeLog(const ImportOptions& o) {
  const std::optional<RangeLogFormat> requested = parseRangeLogFormat(o.format);
  if (!requested) throw std::runtime_error("unknown format '" + o.format + "' (auto, carmen, cmu, duke, mines)");
  ProgressBar progress(o.command);
  const std::string text = readMaybeGzipFile(o.in, "range log");
  const RangeLogFormat format = *requested == RangeLogFormat::Auto ? detectRangeLogFormat(text, o.in) : *requested;
  RangeLogOptions options = readerOptions(o);
  const auto report = [&](double f) { progress.update(0.8 * f); };
  options.carmen.progress = options.cmu.progress = options.duke.progress = options.mines.progress = report;
  const RangeLog log = readRangeLogText(text, o.in, format, options);
  if (log.events.empty()) {
    progress.finish();
    std::string why = "'" + o.in + "' holds no laser or odometry line of the " + rangeLogFormatName(format) +
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
  std::cout << c << ": " << rangeLogFormatName(format) << " log, " << summary(log) << "\n";
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

void addCommonOptions(CLI::App& sub, ImportOptions& o) {
  sub.add_option("-o,--out", o.out, "LCM log to write")->required();
  sub.add_option("--laser-channel", o.laser_channel)->capture_default_str();
  sub.add_option("--odometry-channel", o.odometry_channel)->capture_default_str();
  sub.add_option("--show-malformed", o.show_malformed, "how many malformed lines to list")->capture_default_str();
}

void setupImport(CLI::App& sub) {
  auto o = std::make_shared<ImportOptions>();
  o->command = "import";
  sub.add_option("input", o->in, "range log, plain or .gz: CARMEN .clf, CMU robotdata*.log, Duke loop5.log, Mines exp*.dat")
      ->required()->check(CLI::ExistingFile);
  addCommonOptions(sub, *o);
  sub.add_option("--format", o->format, "auto (from the content), carmen, cmu, duke or mines")
      ->check(CLI::IsMember({"auto", "carmen", "cmu", "duke", "mines"}))->capture_default_str();
  sub.add_option("--no-return-range", o->no_return_range,
                 "ranges at or above this (m) are 'no return' (default per format: CARMEN and CMU 80, Duke 8.18; "
                 "for Mines, the scans' range_max, 5.6)")
      ->check(CLI::NonNegativeNumber);
  sub.add_option("--laser-pose", o->laser_pose,
                 "laser mount x y theta (m, m, rad) (default per format: CMU 0.25 0 0, Mines 0.07 0 0, none for "
                 "CARMEN FLASER and Duke; ROBOTLASER1 lines carry their own)")
      ->expected(3);
  sub.add_option("--period", o->period, "Duke logs, which have no timestamps: seconds between Odometry+Laser pairs")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.callback([o] { importRangeLog(*o); });
}

void setupImportCarmen(CLI::App& sub) {
  auto o = std::make_shared<ImportOptions>();
  o->command = "import-carmen";
  o->format = "carmen";
  o->no_return_range = CarmenOptions{}.no_return_range;
  o->laser_pose = {0.0, 0.0, 0.0};
  sub.add_option("input", o->in, "CARMEN log (.clf)")->required()->check(CLI::ExistingFile);
  addCommonOptions(sub, *o);
  sub.add_option("--no-return-range", o->no_return_range, "ranges at or above this (m) are 'no return'")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--flaser-laser-pose", o->laser_pose,
                 "laser mount x y theta (m, m, rad) for FLASER lines, which do not record it")
      ->expected(3)->capture_default_str();
  sub.callback([o] { importRangeLog(*o); });
}

RegisterCommand reg_import("import", "Convert a range log (CARMEN, CMU, Duke, Mines; plain or gzip) into an LCM log",
                           setupImport);
RegisterCommand reg_carmen("import-carmen", "Convert a CARMEN log (FLASER, ROBOTLASER1, ODOM) into an LCM log "
                           "(import --format carmen)", setupImportCarmen);

}  // namespace
}  // namespace polarslam
