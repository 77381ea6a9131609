// Live replay (config/groups/replay.yaml) against `polarslam run`: the bundled log played with
// lcm-logplayer into the live processes, everything recorded with lcm-logger. One pipeline, one
// configuration: the live final errors (EKF: scan anchors regenerated in the last SLAM_MAP; PSM
// SLAM: anchored poses re-placed by the last PSM_SLAM_GRAPH) must match the offline run's, the
// grids travel on LCM, and the live grid from PSM SLAM's graph is the offline map.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "child_process.hpp"
#include "map_files.hpp"
#include "common/lcm_log.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::readFile;
using polarslam::testing::figure;
using polarslam::testing::readJson;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;
using polarslam::testing::MapServerMap;
using polarslam::testing::occupiedAgreement;
using polarslam::testing::readMapServer;

namespace {

// The log plays 4× faster than real time. The sanitizer build's stages are about 13× slower than
// the optimised ones: at 4× they need more than half of a two-core machine (EKF SLAM about 40 %
// of a core, the grid 35 %), and a slower CI machine would make them fall behind and lose input as
// an overloaded robot would. 2× leaves them a margin.
#ifdef __SANITIZE_ADDRESS__
constexpr const char* kReplaySpeed = "2";
#else
constexpr const char* kReplaySpeed = "4";
#endif

std::map<std::string, long> channelCounts(const std::string& log_path) {
  std::map<std::string, long> counts;
  polarslam::LcmLogReader reader(log_path);
  polarslam::LogEvent event;
  while (reader.next(event)) ++counts[event.channel];
  return counts;
}

/// Where, in a log's message order, each polarslam process reported "stopped", and where the last
/// message of each channel is.
struct LogOrder {
  std::map<std::string, long> stopped, last;
  static long at(const std::map<std::string, long>& where, const std::string& key) {
    const auto it = where.find(key);
    return it == where.end() ? -1 : it->second;
  }
};

LogOrder logOrder(const std::string& log_path) {
  LogOrder order;
  polarslam::LcmLogReader reader(log_path);
  polarslam::LogEvent event;
  polarslam::process_status_t status;
  for (long i = 0; reader.next(event); ++i) {
    order.last[event.channel] = i;
    if (event.channel == "PROCESS_STATUS" && event.decode(status) && status.state == "stopped")
      order.stopped[status.name] = i;
  }
  return order;
}

nlohmann::json runOffline(const std::filesystem::path& dir, const std::string& pipeline, const std::string& config) {
  const auto out = dir / ("offline-" + pipeline);
  EXPECT_EQ(runToEnd({binPath("polarslam"), "run", "--log", sourcePath("logs/office.lcmlog"), "--pipeline", pipeline,
                      "--config", sourcePath(config), "--out", out.string()},
                     dir / ("offline-" + pipeline + ".out"), 300s),
            0)
      << readFile(dir / ("offline-" + pipeline + ".out"));
  return readJson(out / "report.json");
}

nlohmann::json scoreRecorded(const std::filesystem::path& dir, const std::string& recorded, const std::string& channel,
                             const std::string& name = "live") {
  const auto out = dir / (name + "-" + channel);
  EXPECT_EQ(runToEnd({binPath("polarslam"), "run", "--log", recorded, "--pipeline", "recorded", "--pose-channel",
                      channel, "--out", out.string()},
                     dir / ("live-" + channel + ".out"), 120s),
            0)
      << readFile(dir / (name + "-" + channel + ".out"));
  return readJson(out / "report.json");
}

/// `recorded` with everything but the sensor channels written `lag_us` later in the log, as from
/// processes that fell that far behind (a slow or loaded machine): their stamps are then that
/// much older than the sensor messages around them.
void writeWithOutputsLagging(const std::string& recorded, const std::string& out, int64_t lag_us) {
  const std::set<std::string> sensors{"LASER", "ODOMETRY", "SONAR", "GROUND_TRUTH"};
  polarslam::LcmLogReader reader(recorded);
  polarslam::LcmLogWriter writer(out);
  std::deque<polarslam::LogEvent> held;
  polarslam::LogEvent event;
  auto release = [&](int64_t now) {
    for (; !held.empty() && held.front().utime + lag_us <= now; held.pop_front())
      writer.writeRaw(held.front().channel, held.front().utime + lag_us, held.front().data.data(), held.front().data.size());
  };
  while (reader.next(event)) {
    release(event.utime);
    if (sensors.count(event.channel)) writer.writeRaw(event.channel, event.utime, event.data.data(), event.data.size());
    else held.push_back(event);
  }
  release(std::numeric_limits<int64_t>::max() - lag_us);
  writer.close();
}

}  // namespace

TEST(Replay, LiveRunOfTheDefaultLogMatchesTheOfflineRunAndRecordsItsGrids) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-replay-it-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const nlohmann::json offline_ekf = runOffline(dir, "ekf", "config/ekf.yaml");
  const nlohmann::json offline_psm = runOffline(dir, "psm-slam", "config/psm-slam.yaml");

  const std::string log = sourcePath("logs/office.lcmlog");
  const auto run_dir = dir / "live";
  const int launch_exit = runToEnd({"env", "POLARSLAM_REPLAY_LOG=" + log, std::string("POLARSLAM_REPLAY_SPEED=") + kReplaySpeed,
                                    binPath("polarslam-launch"), sourcePath("config/groups/replay.yaml"), "--no-tui",
                                    "--run-dir", run_dir.string()},
                                   dir / "launch.out", 300s);
  const std::string launch_text = readFile(dir / "launch.out");
  ASSERT_EQ(launch_exit, 0) << launch_text;
  EXPECT_NE(launch_text.find("[launch] player is required: stopping everything"), std::string::npos) << launch_text;

  const std::string recorded = (run_dir / "recorded.lcmlog").string();
  const auto sent = channelCounts(log), got = channelCounts(recorded);
  for (const std::string channel : {"LASER", "ODOMETRY", "GROUND_TRUTH"})
    EXPECT_GE(got.count(channel) ? got.at(channel) : 0, sent.at(channel) * 99 / 100) << channel;
  const long scans = sent.at("LASER");
  for (const auto& [channel, at_least] :
       std::map<std::string, long>{{"LASER_FEATURES", scans * 95 / 100}, {"FEATURES", scans * 95 / 100},
                                   {"SCAN_ANCHORS", scans * 95 / 100}, {"PSM_SLAM_POSE", scans * 95 / 100},
                                   {"PSM_SLAM_ANCHORS", scans * 95 / 100}, {"PSM_SLAM_GRAPH", 2}, {"SLAM_MAP", 100},
                                   {"GRID_MAP", 5}, {"PSM_GRID_MAP", 5}})
    EXPECT_GE(got.count(channel) ? got.at(channel) : 0, at_least) << channel << " from the live processes";

  const nlohmann::json live_ekf = scoreRecorded(dir, recorded, "SLAM_POSE");
  const nlohmann::json live_psm = scoreRecorded(dir, recorded, "PSM_SLAM_POSE");
  std::printf("ATE RMSE [m]        offline final  live final  offline online  live online\n");
  std::printf("EKF SLAM            %13.4f  %10.4f  %14.4f  %11.4f\n", figure(offline_ekf, "ate_rmse_m"),
              figure(live_ekf, "ate_rmse_m"), figure(offline_ekf, "online_ate_rmse_m"),
              figure(live_ekf, "online_ate_rmse_m"));
  std::printf("PSM SLAM            %13.4f  %10.4f  %14.4f  %11.4f\n", figure(offline_psm, "ate_rmse_m"),
              figure(live_psm, "ate_rmse_m"), figure(offline_psm, "online_ate_rmse_m"),
              figure(live_psm, "online_ate_rmse_m"));
  EXPECT_NEAR(figure(live_ekf, "ate_rmse_m"), figure(offline_ekf, "ate_rmse_m"), 0.10 * figure(offline_ekf, "ate_rmse_m"));
  EXPECT_NEAR(figure(live_psm, "ate_rmse_m"), figure(offline_psm, "ate_rmse_m"), 0.10 * figure(offline_psm, "ate_rmse_m"));
  EXPECT_EQ(live_psm["recorded"]["final_from"], "anchored poses re-placed by the last pose graph") << live_psm.dump();
  EXPECT_EQ(live_ekf["recorded"]["final_from"], "scan anchors regenerated in the last map") << live_ekf.dump();
  ASSERT_TRUE(live_ekf.contains("messages_dropped")) << "PROCESS_STATUS missing from the recording";

  const MapServerMap offline_map = readMapServer(dir / "offline-psm-slam");
  const MapServerMap live_map = readMapServer(run_dir / "grid-psm");
  ASSERT_GT(offline_map.occupied.size(), 100u);
  EXPECT_GE(occupiedAgreement(offline_map, live_map), 0.95);
  EXPECT_GE(occupiedAgreement(live_map, offline_map), 0.95);
  EXPECT_TRUE(std::filesystem::exists(run_dir / "grid" / "map.pgm"));
  // The recorder stops last (reverse start order): it kept what each stage published on its way
  // out, down to the final map and graph the estimators publish after they report "stopped".
  const LogOrder order = logOrder(recorded);
  for (const std::string stage : {"polarslam-features", "polarslam-fusion", "polarslam-ekf-slam", "polarslam-psm-slam",
                                  "polarslam-grid", "polarslam-grid-psm"})
    EXPECT_TRUE(order.stopped.count(stage)) << stage << " stopped after the recorder";
  EXPECT_GT(order.at(order.last, "SLAM_MAP"), order.at(order.stopped, "polarslam-ekf-slam")) << "no final SLAM_MAP";
  EXPECT_GT(order.at(order.last, "PSM_SLAM_GRAPH"), order.at(order.stopped, "polarslam-psm-slam")) << "no final graph";

  // Processes that fall behind (the sanitizer build, a loaded robot computer) publish outputs
  // stamped seconds behind the sensors: the scoring takes them all, as they came.
  const std::string lagging = (dir / "lagging.lcmlog").string();
  writeWithOutputsLagging(recorded, lagging, 20'000'000);
  for (const auto& [channel, live] : {std::pair{"SLAM_POSE", &live_ekf}, std::pair{"PSM_SLAM_POSE", &live_psm}}) {
    const nlohmann::json late = scoreRecorded(dir, lagging, channel, "lagging");
    EXPECT_EQ(late["trajectory_poses"], (*live)["trajectory_poses"]) << channel;
    EXPECT_DOUBLE_EQ(figure(late, "ate_rmse_m"), figure(*live, "ate_rmse_m")) << channel;
    EXPECT_DOUBLE_EQ(figure(late, "online_ate_rmse_m"), figure(*live, "online_ate_rmse_m")) << channel;
  }

  // The recorded log is an ordinary LCM log: lcm-logplayer plays it again, to its end.
  EXPECT_EQ(runToEnd({"lcm-logplayer", "--speed", "50", recorded}, dir / "replay-again.out", 60s), 0);
  if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir);
}
