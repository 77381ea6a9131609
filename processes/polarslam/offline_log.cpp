#include "offline_log.hpp"

#include <iostream>

#include "common/lcm_convert.hpp"
#include "common/lcm_log.hpp"
#include "common/path_messages.hpp"
#include "common/pose_graph_message.hpp"
#include "common/progress.hpp"
#include "polarslam/process_status_t.hpp"

namespace polarslam {
namespace {

class Dispatcher {
 public:
  Dispatcher(SensorLogSummary& summary, const StreamTimeGateConfig& time_gate)
      : summary_(summary), time_gate_(time_gate) {}

  /// Sensor messages pass the stream time gate; `Estimate`s (what a recorded live run
  /// published) do not: a process that fell behind stamps its outputs with the time of the input
  /// it is working on, seconds behind the sensors, and RecordedEstimator keeps each channel in order.
  enum class Clock { Sensor, Estimate };

  template <typename MsgT, typename CoreT>
  void deliver(const LogEvent& event, const std::function<void(const CoreT&)>& sink, Clock clock = Clock::Sensor) {
    if (!sink) return;
    MsgT msg;
    if (!event.decode(msg)) return reject(event.channel + ": message does not decode as " + MsgT::getTypeName());
    if (clock == Clock::Sensor)
      if (const std::string why = time_gate_.admit(event.channel, msg.utime); !why.empty()) return reject(why);
    CoreT value;
    if (const std::string why = fromLcm(msg, value); !why.empty()) return reject(why);
    ++summary_.messages[event.channel];
    summary_.noteStamp(event.utime);
    sink(value);
  }

 private:
  void reject(const std::string& why) {
    if (summary_.rejected[why]++ == 0) std::cerr << "rejected: " << why << " (further ones counted)\n";
  }
  SensorLogSummary& summary_;
  StreamTimeGate time_gate_;
};

void recordStatus(const LogEvent& event, SensorLogSummary& summary) {
  process_status_t msg;
  if (!event.decode(msg) || msg.name.empty()) return;
  summary.processes[msg.name] = {msg.state, msg.messages_handled, msg.messages_rejected, msg.messages_dropped};
}

}  // namespace

SensorLogSummary visitSensorLog(const std::string& path, const SensorChannelNames& channels,
                                const SensorLogVisitor& visitor, const std::string& progress_label,
                                const StreamTimeGateConfig& time_gate) {
  SensorLogSummary summary;
  LcmLogReader reader(path);
  ProgressBar progress(progress_label.empty() ? "read " + path : progress_label);
  Dispatcher dispatch(summary, time_gate);
  const Dispatcher::Clock estimate = Dispatcher::Clock::Estimate;
  LogEvent event;
  long events = 0;
  while (reader.next(event)) {
    if (event.channel == channels.laser) dispatch.deliver<laser_scan_t>(event, visitor.laser);
    else if (event.channel == channels.sonar) dispatch.deliver<sonar_targets_t>(event, visitor.sonar);
    else if (event.channel == channels.odometry) dispatch.deliver<odometry_t>(event, visitor.odometry);
    else if (event.channel == channels.ground_truth) dispatch.deliver<pose_t>(event, visitor.ground_truth);
    else if (event.channel == channels.estimated_pose) dispatch.deliver<pose_t>(event, visitor.estimated_pose, estimate);
    else if (event.channel == channels.scan_anchors) dispatch.deliver<scan_anchors_t>(event, visitor.scan_anchors, estimate);
    else if (event.channel == channels.slam_map) dispatch.deliver<slam_map_t>(event, visitor.slam_map, estimate);
    else if (event.channel == channels.anchored_poses)
      dispatch.deliver<anchored_pose_t>(event, visitor.anchored_pose, estimate);
    else if (event.channel == channels.pose_graph) dispatch.deliver<pose_graph_t>(event, visitor.pose_graph, estimate);
    else if (event.channel == channels.final_path) dispatch.deliver<path_t>(event, visitor.final_path, estimate);
    else if (event.channel == "PROCESS_STATUS") recordStatus(event, summary);
    if (++events % 256 == 0) progress.update(reader.progress());
  }
  progress.finish();
  reader.printWarnings();
  summary.log_warnings = reader.warnings();
  return summary;
}

}  // namespace polarslam
