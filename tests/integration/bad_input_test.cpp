// Bad input never crashes a process (issue 9). Every consuming process runs at once; on every
// channel it reads it first gets bytes that are not a message, a message of the wrong type, a
// truncated one and one whose array length disagrees with its count, then type-specific
// nonsense: NaN, Inf, negative and huge ranges, 0 and 100 000 beams, unknown sonar kinds,
// duplicates and time going backwards. Then a short simulated drive plays: every process must
// still be running, have counted rejections in PROCESS_STATUS, produce its outputs from the good
// messages, and stop cleanly.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <thread>

#include "child_process.hpp"
#include "common/lcm_log.hpp"
#include "common/process_context.hpp"
#include "polarslam/features_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/process_status_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::sourcePath;

namespace {

namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

template <typename Msg>
std::vector<uint8_t> encode(const Msg& msg) {
  std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

polarslam::laser_scan_t scan(int64_t utime, int64_t seq, std::vector<float> ranges) {
  polarslam::laser_scan_t m{};
  m.utime = utime;
  m.seq = seq;
  m.angle_min = -M_PI / 2;
  m.angle_increment = M_PI / 180;
  m.range_max = 30.0;
  m.num_ranges = static_cast<int32_t>(ranges.size());
  m.ranges = std::move(ranges);
  return m;
}

polarslam::odometry_t odometry(int64_t utime, int64_t seq, double x) {
  polarslam::odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.x = x;
  for (int i = 0; i < 9; i += 4) m.cov[i] = 1e-4;
  return m;
}

class Publisher {
 public:
  explicit Publisher(lcm::LCM& lcm) : lcm_(lcm) {}
  void raw(const std::string& channel, const std::vector<uint8_t>& bytes) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    std::this_thread::sleep_for(2ms);  // the test is about content, not about flooding
  }
  template <typename Msg>
  void send(const std::string& channel, const Msg& msg) { raw(channel, encode(msg)); }

  /// Not a message, the wrong type, truncated, and a count that disagrees with the array.
  template <typename Msg>
  void structural(const std::string& channel, const Msg& valid, size_t count_offset) {
    raw(channel, {1, 2, 3, 4, 5});
    polarslam::process_status_t wrong{};
    wrong.name = "intruder";
    send(channel, wrong);
    std::vector<uint8_t> bytes = encode(valid);
    raw(channel, std::vector<uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() / 2)));
    if (count_offset > 0 && count_offset + 4 <= bytes.size()) {
      bytes[count_offset] = 0x00, bytes[count_offset + 1] = 0x0f, bytes[count_offset + 2] = 0xff, bytes[count_offset + 3] = 0xff;
      raw(channel, bytes);
    }
  }

 private:
  lcm::LCM& lcm_;
};

void sendBadLaser(Publisher& p, int64_t t0) {
  // fingerprint 8, utime 8, seq 8, 4 doubles 32, laser_pose 24: num_ranges at byte 80.
  p.structural("LASER", scan(t0, 1, std::vector<float>(181, 2.0f)), 80);
  p.send("LASER", scan(t0, 2, {}));                                      // zero beams
  p.send("LASER", scan(t0 + 100000, 3, std::vector<float>(100000, 2.0f)));  // 100 000 beams
  p.send("LASER", scan(t0 + 200000, 4, std::vector<float>(181, kNaN)));
  p.send("LASER", scan(t0 + 300000, 5, std::vector<float>(181, kInf)));
  p.send("LASER", scan(t0 + 400000, 6, std::vector<float>(181, -1.0f)));
  p.send("LASER", scan(t0 + 500000, 7, std::vector<float>(181, 1e30f)));
  auto bad_angles = scan(t0 + 600000, 8, std::vector<float>(181, 2.0f));
  bad_angles.angle_increment = std::nan("");
  p.send("LASER", bad_angles);
  p.send("LASER", scan(t0 + 600000, 8, std::vector<float>(181, 2.0f)));  // duplicate seq
  p.send("LASER", scan(t0 - 5000000, 9, std::vector<float>(181, 2.0f)));  // 5 s back in time
}

void sendBadOdometry(Publisher& p, int64_t t0) {
  // fingerprint 8, utime 8, seq 8: no arrays, so no count to corrupt.
  p.structural("ODOMETRY", odometry(t0, 1, 0.0), 0);
  auto nan_pose = odometry(t0 + 20000, 2, 0.0);
  nan_pose.theta = std::nan("");
  p.send("ODOMETRY", nan_pose);
  auto inf_cov = odometry(t0 + 40000, 3, 0.0);
  inf_cov.cov[0] = std::numeric_limits<double>::infinity();
  p.send("ODOMETRY", inf_cov);
  p.send("ODOMETRY", odometry(t0 + 60000, 4, 1e300));
  p.send("ODOMETRY", odometry(t0 + 60000, 4, 0.0));       // duplicate
  p.send("ODOMETRY", odometry(t0 - 5000000, 5, 0.0));     // back in time
}

void sendBadSonar(Publisher& p, int64_t t0) {
  polarslam::sonar_targets_t m{};
  m.utime = t0;
  m.seq = 1;
  m.range_max = 5.0;
  m.field_of_view = 0.5;
  m.num_targets = 3;
  m.targets.resize(3);
  m.targets[0].kind = 99;  // unknown enum value
  m.targets[0].range = 1.0;
  m.targets[1].kind = 0;
  m.targets[1].range = std::nan("");
  m.targets[2].kind = 1;
  m.targets[2].range = -2.0;
  // fingerprint 8, utime 8, seq 8, sensor_id 4, sensor_pose 24, range_max 8, fov 8: count at 68.
  p.structural("SONAR", m, 68);
  p.send("SONAR", m);
}

void sendBadOthers(Publisher& p) {
  polarslam::features_t f{};
  polarslam::pose_t pose{};
  pose.x = std::nan("");
  for (const char* channel : {"LASER_FEATURES", "FEATURES"}) p.structural(channel, f, 0);
  for (const char* channel : {"SLAM_MAP", "SCAN_ANCHORS", "SLAM_POSE", "GOAL", "GRID_REQUEST"}) {
    p.structural(channel, pose, 0);
    p.send(channel, pose);
  }
}

struct Watch {
  std::map<std::string, long> outputs;
  std::map<std::string, polarslam::process_status_t> status;
  void onOutput(const lcm::ReceiveBuffer*, const std::string& channel) { ++outputs[channel]; }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const polarslam::process_status_t* m) { status[m->name] = *m; }
};

}  // namespace

TEST(BadInput, EveryProcessRejectsAndCountsItAndKeepsWorkingOnGoodMessages) {
  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const fs::path dir = fs::temp_directory_path() / ("polarslam-bad-input-it-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string robot = sourcePath("config/robots/default.yaml");
  const std::string log = (dir / "sim.lcmlog").string();
  ChildProcess simulate({binPath("polarslam"), "simulate", "--world", sourcePath("config/worlds/office.yaml"), "--robot",
                         robot, "--seconds", "8", "-o", log},
                        (dir / "simulate.out").string());
  ASSERT_TRUE(simulate.waitFor(60s));
  ASSERT_EQ(simulate.exitCode(), 0);

  Watch watch;
  for (const char* channel : {"LASER_FEATURES", "FEATURES", "SLAM_POSE", "PSM_ODOMETRY", "PSM_SLAM_POSE", "GRID_STATUS"})
    lcm.subscribe(channel, &Watch::onOutput, &watch)->setQueueCapacity(100000);
  lcm.subscribe("PROCESS_STATUS", &Watch::onStatus, &watch)->setQueueCapacity(100000);
  const std::map<std::string, std::vector<std::string>> commands = {
      {"polarslam-features", {binPath("polarslam-features")}},
      {"polarslam-fusion", {binPath("polarslam-fusion"), "--config", robot}},
      {"polarslam-ekf-slam", {binPath("polarslam-ekf-slam"), "--config", robot}},
      {"polarslam-psm", {binPath("polarslam-psm")}},
      {"polarslam-psm-slam", {binPath("polarslam-psm-slam")}},
      {"polarslam-grid", {binPath("polarslam-grid"), "--out", (dir / "grid").string(), "--period", "1"}}};
  std::map<std::string, std::unique_ptr<ChildProcess>> processes;
  for (const auto& [name, argv] : commands)
    processes[name] = std::make_unique<ChildProcess>(argv, (dir / (name + ".log")).string());
  std::this_thread::sleep_for(1500ms);  // let them join the group

  // The bad burst is stamped 20 s before the drive and numbered far from it: the good messages
  // that follow are then in order, as after a real glitch, and their publisher (whose sequence
  // numbers start at 0) reads as one that started over.
  Publisher publisher(lcm);
  polarslam::LcmLogReader reader(log);
  polarslam::LogEvent first;
  ASSERT_TRUE(reader.next(first));
  const int64_t t0 = first.utime - 20000000;
  sendBadLaser(publisher, t0);
  sendBadOdometry(publisher, t0);
  sendBadSonar(publisher, t0);
  sendBadOthers(publisher);
  for (auto end = std::chrono::steady_clock::now() + 1s; std::chrono::steady_clock::now() < end;) lcm.handleTimeout(20);
  const std::map<std::string, long> before = watch.outputs;

  ChildProcess player({"lcm-logplayer", "--speed", "2", log}, (dir / "player.out").string());
  while (player.running()) lcm.handleTimeout(20);
  for (auto end = std::chrono::steady_clock::now() + 2500ms; std::chrono::steady_clock::now() < end;) lcm.handleTimeout(20);

  for (const auto& [name, process] : processes) {
    EXPECT_TRUE(process->running()) << name << " died on bad input; its log: " << dir / (name + ".log");
    ASSERT_TRUE(watch.status.count(name)) << name << " published no PROCESS_STATUS";
    EXPECT_GE(watch.status[name].messages_rejected, 3) << name << " did not count the bad messages";
    EXPECT_GT(watch.status[name].num_reject_kinds, 1) << name;
  }
  // 8 s of drive: 80 scans. Each stage made output from the good messages that followed.
  for (const auto& [channel, at_least] : std::map<std::string, long>{{"LASER_FEATURES", 70}, {"FEATURES", 70},
                                                                     {"SLAM_POSE", 70}, {"PSM_ODOMETRY", 30},
                                                                     {"PSM_SLAM_POSE", 70}, {"GRID_STATUS", 2}}) {
    const long made = watch.outputs[channel] - (before.count(channel) ? before.at(channel) : 0);
    EXPECT_GE(made, at_least) << channel << " after the bad input";
  }
  for (const auto& [name, process] : processes) {
    process->signal(SIGINT);
    ASSERT_TRUE(process->waitFor(15s)) << name;
    EXPECT_EQ(process->exitCode(), 0) << name;
  }
  if (!HasFailure()) fs::remove_all(dir);
}
