// polarslam import-carmen IN.clf -o OUT.lcmlog: a CARMEN log (FLASER, ROBOTLASER1, ODOM) as an
// LCM log of LASER and ODOMETRY messages, keeping the log's timestamps and their order.
#include <algorithm>
#include <iostream>
#include <sstream>

#include "command_registry.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"
#include "io/carmen.hpp"

namespace polarslam {
namespace {

struct ImportOptions {
  std::string in, out;
  std::string laser_channel = "LASER", odometry_channel = "ODOMETRY";
  double no_return_range = 80.0;
  std::vector<double> flaser_laser_pose{0.0, 0.0, 0.0};
  size_t show_malformed = 5;
};

std::string summary(const CarmenLog& log) {
  std::ostringstream s;
  s << log.lines << " lines: " << log.flaser_lines << " FLASER, " << log.robotlaser_lines << " ROBOTLASER1, "
    << log.odom_lines << " ODOM, " << log.comment_lines << " comments/blank";
  for (const auto& [kind, count] : log.skipped_kinds) s << ", " << count << " " << kind << " (skipped)";
  s << ", " << log.malformed_count << " malformed";
  return s.str();
}

void importCarmen(const ImportOptions& o) {
  CarmenOptions options;
  options.no_return_range = o.no_return_range;
  options.flaser_laser_pose = {o.flaser_laser_pose[0], o.flaser_laser_pose[1], o.flaser_laser_pose[2]};
  ProgressBar progress("import-carmen");
  options.progress = [&](double f) { progress.update(0.8 * f); };
  const CarmenLog log = readCarmenLogFile(o.in, options);
  if (log.events.empty()) {
    progress.finish();
    throw std::runtime_error("'" + o.in + "' holds no FLASER, ROBOTLASER1 or ODOM line (" + summary(log) + ")");
  }
  LcmLogWriter writer(o.out);
  int64_t lasers = 0, odometries = 0;
  for (size_t k = 0; k < log.events.size(); ++k) {
    const CarmenEvent& e = log.events[k];
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

  std::cout << "import-carmen: " << summary(log) << "\n";
  std::cout << "import-carmen: wrote " << lasers << " " << o.laser_channel << " and " << odometries << " "
            << o.odometry_channel << " messages to " << o.out << "\n";
  if (log.odometry_from_robotlaser)
    std::cout << "import-carmen: no ODOM lines: odometry taken from the ROBOTLASER1 robot poses\n";
  if (log.laser_time_reversals > 0)
    std::cout << "import-carmen: " << log.laser_time_reversals
              << " laser timestamps step back in time (kept in file order, as relations expect)\n";
  if (log.unusual_beam_counts > 0)
    std::cout << "import-carmen: " << log.unusual_beam_counts
              << " FLASER lines with a beam count other than 180/181/360/361: assumed to span 180 degrees\n";
  const size_t shown = std::min(o.show_malformed, log.malformed.size());
  for (size_t k = 0; k < shown; ++k)
    std::cout << "  " << o.in << ":" << log.malformed[k].line << ": " << log.malformed[k].reason << "\n";
  if (log.malformed_count > static_cast<int64_t>(shown))
    std::cout << "  ... and " << log.malformed_count - static_cast<int64_t>(shown) << " more malformed lines\n";
}

void setupImportCarmen(CLI::App& sub) {
  auto o = std::make_shared<ImportOptions>();
  sub.add_option("input", o->in, "CARMEN log (.clf)")->required()->check(CLI::ExistingFile);
  sub.add_option("-o,--out", o->out, "LCM log to write")->required();
  sub.add_option("--laser-channel", o->laser_channel)->capture_default_str();
  sub.add_option("--odometry-channel", o->odometry_channel)->capture_default_str();
  sub.add_option("--no-return-range", o->no_return_range, "ranges at or above this (m) are 'no return'")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--flaser-laser-pose", o->flaser_laser_pose,
                 "laser mount x y theta (m, m, rad) for FLASER lines, which do not record it")
      ->expected(3)->capture_default_str();
  sub.add_option("--show-malformed", o->show_malformed, "how many malformed lines to list")->capture_default_str();
  sub.callback([o] { importCarmen(*o); });
}

RegisterCommand reg("import-carmen", "Convert a CARMEN log (FLASER, ROBOTLASER1, ODOM) into an LCM log", setupImportCarmen);

}  // namespace
}  // namespace polarslam
