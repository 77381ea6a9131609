// Live replay (config/groups/replay.yaml): a simulated log played with lcm-logplayer into the live
// processes, everything recorded with lcm-logger; the launcher stops when the log has played out.
// The recorded log holds the live SLAM poses, which score against the ground truth like an
// offline run, and it replays again.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "child_process.hpp"
#include "common/lcm_log.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::readFile;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;

namespace {

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

nlohmann::json readJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

}  // namespace

TEST(Replay, LogPlayedIntoTheLiveProcessesIsRecordedScoredAndReplaysAgain) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-replay-it-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_EQ(runToEnd({binPath("polarslam"), "simulate", "--world", sourcePath("config/worlds/office.yaml"), "--robot",
                      sourcePath("config/robots/default.yaml"), "--seconds", "25", "-o", sim_log},
                     dir / "simulate.out", 60s),
            0);

  const auto run_dir = dir / "live";
  const int launch_exit = runToEnd({"env", "POLARSLAM_REPLAY_LOG=" + sim_log, "POLARSLAM_REPLAY_SPEED=4",
                                    binPath("polarslam-launch"), sourcePath("config/groups/replay.yaml"), "--no-tui",
                                    "--run-dir", run_dir.string()},
                                   dir / "launch.out", 120s);
  const std::string launch_text = readFile(dir / "launch.out");
  ASSERT_EQ(launch_exit, 0) << launch_text;
  EXPECT_NE(launch_text.find("[launch] player is required: stopping everything"), std::string::npos) << launch_text;

  const std::string recorded = (run_dir / "recorded.lcmlog").string();
  const auto sent = channelCounts(sim_log), got = channelCounts(recorded);
  for (const std::string channel : {"LASER", "ODOMETRY", "GROUND_TRUTH"})
    EXPECT_GE(got.count(channel) ? got.at(channel) : 0, sent.at(channel) * 95 / 100) << channel;
  // 25 s of log: 250 scans, so about that many per-scan messages; the map once a second.
  for (const auto& [channel, at_least] : std::map<std::string, long>{{"LASER_FEATURES", 200}, {"FEATURES", 200},
                                                                     {"SLAM_POSE", 200}, {"SCAN_ANCHORS", 200},
                                                                     {"PSM_SLAM_POSE", 200}, {"SLAM_MAP", 15}})
    EXPECT_GE(got.count(channel) ? got.at(channel) : 0, at_least) << channel << " from the live processes";
  EXPECT_TRUE(std::filesystem::exists(run_dir / "grid" / "map.pgm"));
  // The recorder stops last (reverse start order): it kept what each stage published on its way
  // out, down to the final map and graph the estimators publish after they report "stopped".
  const LogOrder order = logOrder(recorded);
  for (const std::string stage : {"polarslam-features", "polarslam-fusion", "polarslam-ekf-slam", "polarslam-psm-slam",
                                  "polarslam-grid"})
    EXPECT_TRUE(order.stopped.count(stage)) << stage << " stopped after the recorder";
  EXPECT_GT(order.at(order.last, "SLAM_MAP"), order.at(order.stopped, "polarslam-ekf-slam")) << "no final SLAM_MAP";
  EXPECT_GT(order.at(order.last, "PSM_SLAM_GRAPH"), order.at(order.stopped, "polarslam-psm-slam")) << "no final graph";

  for (const std::string channel : {"SLAM_POSE", "PSM_SLAM_POSE"}) {
    const auto out = dir / ("eval-" + channel);
    ASSERT_EQ(runToEnd({binPath("polarslam"), "run", "--log", recorded, "--pipeline", "recorded", "--pose-channel",
                        channel, "--out", out.string()},
                       dir / ("eval-" + channel + ".out"), 60s),
              0);
    const nlohmann::json report = readJson(out / "report.json");
    ASSERT_TRUE(report.contains("ate_rmse_m")) << report.dump();
    EXPECT_LT(report["ate_rmse_m"].get<double>(), 0.3) << channel;
    EXPECT_GT(report["trajectory_poses"].get<long>(), 100) << channel;
  }

  // The recorded log is an ordinary LCM log: lcm-logplayer plays it again, to its end.
  EXPECT_EQ(runToEnd({"lcm-logplayer", "--speed", "20", recorded}, dir / "replay-again.out", 60s), 0);
  std::filesystem::remove_all(dir);
}
