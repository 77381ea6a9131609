// Stopping a polarslam process: SIGINT ends its loop, but the input already queued is handled
// before its exit work (processes/common/process_context.cpp). polarslam-launch stops stages in
// reverse start order, so this is how a stage's last messages still reach the stage below it.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include "child_process.hpp"
#include "common/process_context.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::process_status_t;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::readFile;

namespace {

using Clock = std::chrono::steady_clock;

/// A scan from the middle of a 4 m x 6 m room: walls the feature extractor fits lines to.
polarslam::laser_scan_t roomScan(int64_t utime, int64_t seq) {
  polarslam::laser_scan_t m{};
  m.utime = utime;
  m.seq = seq;
  m.angle_min = -M_PI / 2;
  m.angle_increment = M_PI / 180;
  m.range_max = 30.0;
  for (int i = 0; i <= 180; ++i) {
    const double a = m.angle_min + i * m.angle_increment;
    const double to_front = 2.0 / std::max(std::abs(std::cos(a)), 1e-9), to_side = 3.0 / std::max(std::abs(std::sin(a)), 1e-9);
    m.ranges.push_back(static_cast<float>(std::min(to_front, to_side)));
  }
  m.num_ranges = static_cast<int32_t>(m.ranges.size());
  return m;
}

/// PROCESS_STATUS messages and a count of one output channel.
class Watch {
 public:
  Watch(lcm::LCM& lcm, const std::string& output_channel) : lcm_(lcm) {
    lcm_.subscribe("PROCESS_STATUS", &Watch::onStatus, this)->setQueueCapacity(10000);
    lcm_.subscribe(output_channel, &Watch::onOutput, this)->setQueueCapacity(10000);
  }
  std::optional<process_status_t> waitForStatus(int pid, const std::string& state, std::chrono::milliseconds timeout) {
    for (const auto end = Clock::now() + timeout;; lcm_.handleTimeout(20)) {
      for (const auto& m : statuses_)
        if (m.pid == pid && m.state == state) return m;
      if (Clock::now() >= end) return std::nullopt;
    }
  }
  /// Handles what is still queued or on its way.
  void drain() {
    while (lcm_.handleTimeout(300) > 0) {
    }
  }
  int outputs() const { return outputs_; }

 private:
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const process_status_t* m) { statuses_.push_back(*m); }
  void onOutput(const lcm::ReceiveBuffer*, const std::string&) { ++outputs_; }
  lcm::LCM& lcm_;
  std::vector<process_status_t> statuses_;
  int outputs_ = 0;
};

}  // namespace

TEST(ProcessStop, InputQueuedAtTheStopSignalIsHandledBeforeTheExit) {
  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-stop-it-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "features.log").string();
  Watch watch(lcm, "LASER_FEATURES");
  ChildProcess features({binPath("polarslam-features"), "--odometry-channel", ""}, log);
  ASSERT_TRUE(watch.waitForStatus(features.pid(), "running", 15s).has_value()) << readFile(log);

  // Published far faster than lines are fitted to them: at the SIGINT most scans are still queued.
  // (80 kB in all: well inside LCM's receive buffers, so none is dropped for lack of room.)
  constexpr int kScans = 100;
  const int64_t t0 = polarslam::nowUtime();
  for (int i = 0; i < kScans; ++i) {
    const polarslam::laser_scan_t scan = roomScan(t0 + i * 100000, i + 1);
    lcm.publish("LASER", &scan);
  }
  features.signal(SIGINT);

  ASSERT_TRUE(features.waitFor(30s)) << readFile(log);
  EXPECT_EQ(features.exitCode(), 0) << readFile(log);
  const auto stopped = watch.waitForStatus(features.pid(), "stopped", 10s);
  ASSERT_TRUE(stopped.has_value()) << readFile(log);
  EXPECT_EQ(stopped->messages_handled, kScans) << readFile(log);
  EXPECT_EQ(stopped->messages_rejected, 0);
  EXPECT_EQ(stopped->messages_dropped, 0);
  watch.drain();
  EXPECT_EQ(watch.outputs(), kScans) << "LASER_FEATURES published for the scans handled after the SIGINT";
  if (!HasFailure()) std::filesystem::remove_all(dir);
}
