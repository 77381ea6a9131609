// polarslam-features over real LCM: a simulated log replayed with lcm-logplayer comes out as
// LASER_FEATURES, one message per scan, identical to the offline `polarslam features` output;
// malformed scans are rejected and counted in PROCESS_STATUS.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "child_process.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "polarslam/features_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::sourcePath;

namespace {

struct FeaturesListener {
  std::map<int64_t, polarslam::FeatureSet> by_utime;
  int undecodable = 0;
  int64_t rejected = -1;
  void onFeatures(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::features_t msg;
    polarslam::FeatureSet set;
    if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || !polarslam::fromLcm(msg, set).empty()) {
      ++undecodable;
      return;
    }
    by_utime[set.utime] = set;
  }
  void onStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::process_status_t msg;
    if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0 && msg.name == "polarslam-features")
      rejected = msg.messages_rejected;
  }
};

}  // namespace

TEST(FeaturesProcess, ReplayedLogGivesTheOfflineFeaturesAndBadScansAreCounted) {
  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-it-features-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "sim.lcmlog").string(), jsonl = (dir / "features.jsonl").string();
  const std::string robot = sourcePath("config/robots/default.yaml");
  ChildProcess simulate({binPath("polarslam"), "simulate", "--world", sourcePath("config/worlds/room.yaml"), "--robot",
                         robot, "--seconds", "3", "-o", log},
                        (dir / "simulate.log").string());
  ASSERT_TRUE(simulate.waitFor(60s));
  ASSERT_EQ(simulate.exitCode(), 0);
  ChildProcess offline({binPath("polarslam"), "features", "--log", log, "--out", jsonl, "--config", robot},
                       (dir / "offline.log").string());
  ASSERT_TRUE(offline.waitFor(60s));
  ASSERT_EQ(offline.exitCode(), 0);

  FeaturesListener listener;
  lcm.subscribe("LASER_FEATURES", &FeaturesListener::onFeatures, &listener);
  lcm.subscribe("PROCESS_STATUS", &FeaturesListener::onStatus, &listener);
  ChildProcess features({binPath("polarslam-features"), "--config", robot}, (dir / "features.log").string());
  std::this_thread::sleep_for(700ms);  // let it join the group
  ChildProcess player({"lcm-logplayer", "--speed", "3", log}, (dir / "player.log").string());
  while (player.running()) lcm.handleTimeout(20);
  const std::vector<uint8_t> garbage = {1, 2, 3, 4, 5};
  lcm.publish("LASER", garbage.data(), static_cast<unsigned>(garbage.size()));
  const auto end = std::chrono::steady_clock::now() + 3s;
  while (std::chrono::steady_clock::now() < end) lcm.handleTimeout(50);
  features.signal(SIGINT);
  ASSERT_TRUE(features.waitFor(10s));
  EXPECT_EQ(features.exitCode(), 0);
  while (lcm.handleTimeout(100) > 0) {
  }

  EXPECT_EQ(listener.undecodable, 0);
  EXPECT_GE(listener.rejected, 1) << "the garbage LASER message is counted";
  std::ifstream in(jsonl);
  std::string line;
  int compared = 0;
  while (std::getline(in, line)) {
    const nlohmann::json scan = nlohmann::json::parse(line);
    const auto it = listener.by_utime.find(scan["utime"].get<int64_t>());
    ASSERT_NE(it, listener.by_utime.end()) << "no LASER_FEATURES for scan " << scan["utime"];
    const polarslam::FeatureSet& live = it->second;
    EXPECT_EQ(live.frame, "laser");
    ASSERT_EQ(live.lines.size(), scan["lines"].size());
    ASSERT_EQ(live.corners.size(), scan["corners"].size());
    for (size_t k = 0; k < live.lines.size(); ++k) {
      EXPECT_NEAR(live.lines[k].alpha, scan["lines"][k]["alpha"].get<double>(), 1e-12);
      EXPECT_NEAR(live.lines[k].d, scan["lines"][k]["d"].get<double>(), 1e-12);
      EXPECT_EQ(live.lines[k].num_points, scan["lines"][k]["n"].get<int>());
    }
    ++compared;
  }
  EXPECT_GE(compared, 25);  // 3 s at 10 Hz
  EXPECT_EQ(compared, static_cast<int>(listener.by_utime.size()));
}
