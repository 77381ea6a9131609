#pragma once
// A simulated drive recorded as polarslam-psm-slam's journal would hold it: the laser and
// odometry messages in arrival order, with the ground truth beside. For tests and benchmarks of
// crash recovery that replay parts of it into a PsmSlamSession (no LCM).
#include <cstddef>
#include <cstdint>
#include <variant>
#include <vector>

#include "pipeline/psm_slam_session.hpp"
#include "sim/simulator.hpp"

namespace polarslam::testing {

struct SessionRecording : SimSink {
  using Message = std::variant<LaserScan, OdometryReading>;
  std::vector<Message> messages;
  std::vector<PoseStamped> truth;

  void onLaser(const LaserScan& scan) override { messages.emplace_back(scan); }
  void onSonar(const SonarScan&) override {}
  void onOdometry(const OdometryReading& odometry) override { messages.emplace_back(odometry); }
  void onGroundTruth(const PoseStamped& pose) override { truth.push_back(pose); }

  int64_t utime(size_t k) const {
    return std::visit([](const auto& m) { return m.utime; }, messages[k]);
  }
  /// Feeds message k to `session`; a scan's online pose is appended to `poses` when given.
  void feed(PsmSlamSession& session, size_t k, std::vector<PoseStamped>* poses = nullptr) const {
    if (const auto* scan = std::get_if<LaserScan>(&messages[k])) {
      const PoseStamped pose = session.onLaser(*scan).pose;
      if (poses) poses->push_back(pose);
    } else {
      session.onOdometry(std::get<OdometryReading>(messages[k]));
    }
  }
};

}  // namespace polarslam::testing
