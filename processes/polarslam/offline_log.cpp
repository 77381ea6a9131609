#include "offline_log.hpp"

#include <iostream>

#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/progress.hpp"

namespace polarslam {
namespace {

class Dispatcher {
 public:
  explicit Dispatcher(SensorLogSummary& summary) : summary_(summary) {}

  template <typename MsgT, typename CoreT>
  void deliver(const LogEvent& event, const std::function<void(const CoreT&)>& sink) {
    if (!sink) return;
    MsgT msg;
    if (!event.decode(msg)) return reject(event.channel + ": message does not decode as " + MsgT::getTypeName());
    CoreT value;
    if (const std::string why = fromLcm(msg, value); !why.empty()) return reject(why);
    ++summary_.messages[event.channel];
    if (summary_.first_utime == 0) summary_.first_utime = event.utime;
    summary_.last_utime = event.utime;
    sink(value);
  }

 private:
  void reject(const std::string& why) {
    if (summary_.rejected[why]++ == 0) std::cerr << "rejected: " << why << " (further ones counted)\n";
  }
  SensorLogSummary& summary_;
};

}  // namespace

SensorLogSummary visitSensorLog(const std::string& path, const SensorChannelNames& channels,
                                const SensorLogVisitor& visitor, const std::string& progress_label) {
  SensorLogSummary summary;
  LcmLogReader reader(path);
  ProgressBar progress(progress_label.empty() ? "read " + path : progress_label);
  Dispatcher dispatch(summary);
  LogEvent event;
  long events = 0;
  while (reader.next(event)) {
    if (event.channel == channels.laser) dispatch.deliver<laser_scan_t>(event, visitor.laser);
    else if (event.channel == channels.sonar) dispatch.deliver<sonar_targets_t>(event, visitor.sonar);
    else if (event.channel == channels.odometry) dispatch.deliver<odometry_t>(event, visitor.odometry);
    else if (event.channel == channels.ground_truth) dispatch.deliver<pose_t>(event, visitor.ground_truth);
    else if (event.channel == channels.estimated_pose) dispatch.deliver<pose_t>(event, visitor.estimated_pose);
    if (++events % 256 == 0) progress.update(reader.progress());
  }
  progress.finish();
  return summary;
}

}  // namespace polarslam
