// bench_load: the whole live pipeline under load (issue 9). The simulator publishes at 1× and at
// K× real time into polarslam-features → -fusion → -ekf-slam, -psm-slam and -grid, all real
// processes over real LCM (run inside scripts/with-netns). A listener counts per channel the
// messages, the sequence gaps (drops) and, for every message derived from a laser scan, the
// latency from the scan's arrival to the derived message's arrival (p50 / p99 per stage).
// Goal: no drops at 1×.
//
//   bench_load [--seconds 30] [--speeds 1,10] [--world W]
#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <signal.h>
#include <string>
#include <vector>

#include "common/process_context.hpp"
#include "integration/child_process.hpp"
#include "polarslam/process_status_t.hpp"

using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::sourcePath;
using namespace std::chrono_literals;

namespace {

using Clock = std::chrono::steady_clock;

/// Every polarslam message type starts with int64 utime, int64 seq after the 8-byte fingerprint.
bool readHeader(const lcm::ReceiveBuffer* rbuf, int64_t& utime, int64_t& seq) {
  if (rbuf->data_size < 24) return false;
  const auto* b = static_cast<const uint8_t*>(rbuf->data);
  auto be64 = [&](size_t at) {
    uint64_t v = 0;
    for (size_t i = 0; i < 8; ++i) v = (v << 8) | b[at + i];
    return static_cast<int64_t>(v);
  };
  utime = be64(8);
  seq = be64(16);
  return true;
}

struct ChannelStats {
  long messages = 0, gaps = 0, repeats = 0;
  int64_t last_seq = -1;
  std::vector<double> latency_ms;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

class Listener {
 public:
  explicit Listener(lcm::LCM& lcm) {
    for (const char* channel : {"LASER", "ODOMETRY", "SONAR", "LASER_FEATURES", "FEATURES", "SLAM_POSE", "SCAN_ANCHORS",
                                "SLAM_MAP", "PSM_SLAM_POSE"})
      lcm.subscribe(channel, &Listener::onMessage, this)->setQueueCapacity(100000);
    lcm.subscribe("PROCESS_STATUS", &Listener::onStatus, this)->setQueueCapacity(100000);
  }
  const std::map<std::string, ChannelStats>& channels() const { return channels_; }
  const std::map<std::string, polarslam::process_status_t>& statuses() const { return statuses_; }

 private:
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto now = Clock::now();
    int64_t utime = 0, seq = 0;
    if (!readHeader(rbuf, utime, seq)) return;
    ChannelStats& s = channels_[channel];
    ++s.messages;
    if (s.last_seq >= 0 && seq <= s.last_seq) ++s.repeats;
    else if (s.last_seq >= 0) s.gaps += seq - s.last_seq - 1;
    s.last_seq = std::max(s.last_seq, seq);
    if (channel == "LASER") laser_arrival_[utime] = now;
    else if (channel == "ODOMETRY") odometry_arrival_[utime] = now;
    else if (channel != "SONAR") latency(s, utime, now);  // sonar is a source too
  }
  void latency(ChannelStats& s, int64_t utime, Clock::time_point now) {
    auto arrival = [utime](const std::map<int64_t, Clock::time_point>& m) -> const Clock::time_point* {
      const auto it = m.find(utime);
      return it == m.end() ? nullptr : &it->second;
    };
    const Clock::time_point* source = arrival(laser_arrival_);
    if (!source) source = arrival(odometry_arrival_);
    if (source) s.latency_ms.push_back(std::chrono::duration<double, std::milli>(now - *source).count());
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const polarslam::process_status_t* m) {
    statuses_[m->name] = *m;
  }
  std::map<std::string, ChannelStats> channels_;
  std::map<int64_t, Clock::time_point> laser_arrival_, odometry_arrival_;
  std::map<std::string, polarslam::process_status_t> statuses_;
};

struct Options {
  double seconds = 30.0;
  std::vector<double> speeds = {1.0, 10.0};
  std::string world = sourcePath("config/worlds/office.yaml");
  std::string robot = sourcePath("config/robots/default.yaml");
};

void runAtSpeed(const Options& o, double speed) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-bench-load-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  if (!lcm.good()) throw std::runtime_error("LCM unavailable: run through scripts/with-netns (scripts/bench-load does)");
  Listener listener(lcm);
  std::vector<std::unique_ptr<ChildProcess>> stages;
  auto start = [&](std::vector<std::string> argv) {
    const std::string log = (dir / (argv[0] + ".log")).string();
    argv[0] = binPath(argv[0]);
    stages.push_back(std::make_unique<ChildProcess>(argv, log));
  };
  start({"polarslam-features"});
  start({"polarslam-fusion", "--config", o.robot});
  start({"polarslam-ekf-slam", "--config", o.robot});
  start({"polarslam-psm-slam"});
  start({"polarslam-grid", "--out", (dir / "grid").string()});
  const auto settle = Clock::now() + 1500ms;
  while (Clock::now() < settle) lcm.handleTimeout(20);
  ChildProcess sim({binPath("polarslam-sim"), "--world", o.world, "--robot", o.robot, "--speed", std::to_string(speed),
                    "--seconds", std::to_string(o.seconds)},
                   (dir / "sim.log").string());
  const auto limit = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds / speed + 60.0));
  while (sim.running() && Clock::now() < limit) lcm.handleTimeout(20);
  const auto drain = Clock::now() + 2s;  // let the stages finish what they hold
  while (Clock::now() < drain) lcm.handleTimeout(20);
  for (auto& stage : stages) stage->signal(SIGINT);
  for (auto& stage : stages) stage->waitFor(10s);
  while (lcm.handleTimeout(100) > 0) {
  }

  std::printf("\n=== %.0f s simulated at %gx real time\n", o.seconds, speed);
  std::printf("%-16s %9s %7s %8s %12s %12s\n", "channel", "messages", "gaps", "repeats", "p50 ms", "p99 ms");
  long total_gaps = 0;
  for (const auto& [name, s] : listener.channels()) {
    total_gaps += s.gaps;
    if (s.latency_ms.empty())
      std::printf("%-16s %9ld %7ld %8ld %12s %12s\n", name.c_str(), s.messages, s.gaps, s.repeats, "-", "-");
    else
      std::printf("%-16s %9ld %7ld %8ld %12.2f %12.2f\n", name.c_str(), s.messages, s.gaps, s.repeats,
                  percentile(s.latency_ms, 0.5), percentile(s.latency_ms, 0.99));
  }
  std::printf("%-20s %9s %9s %9s\n", "process (last status)", "handled", "rejected", "dropped");
  long process_drops = 0;
  for (const auto& [name, m] : listener.statuses()) {
    process_drops += m.messages_dropped;
    std::printf("%-20s %9lld %9lld %9lld\n", name.c_str(), static_cast<long long>(m.messages_handled),
                static_cast<long long>(m.messages_rejected), static_cast<long long>(m.messages_dropped));
  }
  std::printf("drops seen by the listener: %ld; reported by the processes: %ld%s\n", total_gaps, process_drops,
              speed <= 1.0 ? (total_gaps + process_drops == 0 ? "  (goal at 1x: none — MET)" : "  (goal at 1x: none — NOT MET)")
                           : "");
  std::filesystem::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_load: the live pipeline at 1x and Kx real time: drops and latency per stage"};
  Options o;
  app.add_option("--seconds", o.seconds, "simulated seconds per run")->capture_default_str();
  app.add_option("--speeds", o.speeds, "simulator speeds, each run in turn")->delimiter(',')->capture_default_str();
  app.add_option("--world", o.world)->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--robot", o.robot)->check(CLI::ExistingFile)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    for (double speed : o.speeds) runAtSpeed(o, speed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_load: %s\n", e.what());
    return 1;
  }
  return 0;
}
