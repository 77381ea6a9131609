// Fault injection (issue 16): the live replay group (config/groups/replay.yaml) plays the default
// log for three minutes while a stage picked at random is killed with SIGKILL every 5-15 s, and
// one odometry message stamped an hour in the future is published among the real ones. The
// launcher restarts each killed stage, the stateful ones resume from their journals (PSM SLAM from
// its last snapshot and the journal since), the time gate rejects the future message; the final
// ATE of both SLAMs stays within 10% above the undisturbed (offline) run's, and no process of the
// group outlives the launcher.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "child_process.hpp"
#include "common/process_context.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::freshDir;
using polarslam::testing::readFile;
using polarslam::testing::readJson;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;

namespace {

namespace fs = std::filesystem;

nlohmann::json runReport(const fs::path& dir, const std::string& name, std::vector<std::string> args) {
  const fs::path out = dir / name;
  args.insert(args.begin(), {binPath("polarslam"), "run"});
  args.insert(args.end(), {"--out", out.string()});
  EXPECT_EQ(runToEnd(args, dir / (name + ".out"), 300s), 0) << readFile(dir / (name + ".out"));
  return readJson(out / "report.json");
}

double ate(const nlohmann::json& report) { return report.value("ate_rmse_m", std::nan("")); }

/// Processes whose environment names this run folder: the group's, wherever they were started.
std::vector<int> processesOfRun(const fs::path& run_dir) {
  const std::string marker = "POLARSLAM_RUN_DIR=" + fs::absolute(run_dir).string();
  std::vector<int> pids;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream environ(entry.path() / "environ", std::ios::binary);
    std::string variable;
    while (std::getline(environ, variable, '\0'))
      if (variable == marker) pids.push_back(std::stoi(name));
  }
  return pids;
}

const std::vector<std::string> kStages{"features", "fusion", "ekf-slam", "psm-slam", "grid", "grid-psm"};

}  // namespace

TEST(FaultInjection, RandomKillsAndAFutureOdometryLeaveTheFinalMapsAsAccurateAsAnUndisturbedRun) {
  const fs::path dir = freshDir("faults-it");
  const std::string log = sourcePath("logs/office.lcmlog");
  const nlohmann::json undisturbed_ekf =
      runReport(dir, "offline-ekf", {"--log", log, "--pipeline", "ekf", "--config", sourcePath("config/ekf.yaml")});
  const nlohmann::json undisturbed_psm = runReport(
      dir, "offline-psm-slam", {"--log", log, "--pipeline", "psm-slam", "--config", sourcePath("config/psm-slam.yaml")});

  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  std::map<std::string, int> running;  // stage -> pid, from the launcher's PROCESS_STATUS
  polarslam::odometry_t latest_odometry{};
  struct Sink {
    std::map<std::string, int>* running;
    polarslam::odometry_t* latest_odometry;
    void status(const lcm::ReceiveBuffer*, const std::string&, const polarslam::process_status_t* m) {
      if (m->state == "running" && m->pid > 0) (*running)[m->name] = m->pid;
      else running->erase(m->name);
    }
    void odometry(const lcm::ReceiveBuffer*, const std::string&, const polarslam::odometry_t* m) {
      *latest_odometry = *m;
    }
  } sink{&running, &latest_odometry};
  lcm.subscribe("PROCESS_STATUS", &Sink::status, &sink);
  lcm.subscribe("ODOMETRY", &Sink::odometry, &sink);

  const fs::path run_dir = dir / "live";
  // 0.85x: the 154 s log plays for three minutes.
  ChildProcess launcher({"env", "POLARSLAM_REPLAY_LOG=" + log, "POLARSLAM_REPLAY_SPEED=0.85",
                         "POLARSLAM_BRIDGE_PORT=18765", binPath("polarslam-launch"),
                         sourcePath("config/groups/replay.yaml"), "--no-tui", "--run-dir", run_dir.string()},
                        (dir / "launch.out").string());
  std::mt19937 random(16);
  std::uniform_int_distribution<int> pause_ms(5000, 15000);
  std::uniform_int_distribution<size_t> pick(0, kStages.size() - 1);
  const auto start = std::chrono::steady_clock::now();
  auto next_kill = start + std::chrono::milliseconds(pause_ms(random));
  bool future_sent = false;
  std::vector<std::string> killed;
  while (launcher.running() && std::chrono::steady_clock::now() - start < 400s) {
    lcm.handleTimeout(50);
    const auto now = std::chrono::steady_clock::now();
    if (!future_sent && now - start > 60s && latest_odometry.utime > 0) {
      polarslam::odometry_t future = latest_odometry;  // a real reading with a clock an hour ahead
      future.utime += 3600LL * 1000000;
      lcm.publish("ODOMETRY", &future);
      future_sent = true;
    }
    if (now < next_kill || now - start > 180s) continue;
    next_kill = now + std::chrono::milliseconds(pause_ms(random));
    const std::string& stage = kStages[pick(random)];
    const auto found = running.find(stage);
    if (found == running.end()) continue;  // down already (still restarting)
    if (kill(found->second, SIGKILL) == 0) killed.push_back(stage);
    running.erase(found);
  }
  ASSERT_TRUE(launcher.waitFor(60s)) << readFile(dir / "launch.out");
  EXPECT_EQ(launcher.exitCode(), 0) << readFile(dir / "launch.out");
  EXPECT_TRUE(future_sent);
  EXPECT_GE(killed.size(), 12u) << "a kill every 5-15 s for three minutes";
  std::this_thread::sleep_for(500ms);
  EXPECT_TRUE(processesOfRun(run_dir).empty()) << "processes left behind by the launcher";

  const std::string recorded = (run_dir / "recorded.lcmlog").string();
  const nlohmann::json live_ekf = runReport(dir, "live-ekf", {"--log", recorded, "--pipeline", "recorded", "--pose-channel", "SLAM_POSE"});
  const nlohmann::json live_psm =
      runReport(dir, "live-psm-slam", {"--log", recorded, "--pipeline", "recorded", "--pose-channel", "PSM_SLAM_POSE"});
  std::ostringstream kills;
  for (const std::string& stage : killed) kills << " " << stage;
  std::printf("killed (SIGKILL):%s\n", kills.str().c_str());
  std::printf("final ATE RMSE [m]  undisturbed  under faults\n");
  std::printf("EKF SLAM            %11.4f  %12.4f\n", ate(undisturbed_ekf), ate(live_ekf));
  std::printf("PSM SLAM            %11.4f  %12.4f\n", ate(undisturbed_psm), ate(live_psm));
  // No worse than 10% above the undisturbed run. PSM SLAM resumed from a snapshot (taken every
  // 60 s) may well end better: its filter restarts with each reference scan's uncertainty as seen
  // from the robot, which lets through loop closures the uninterrupted filter gates out.
  EXPECT_LE(ate(live_ekf), 1.10 * ate(undisturbed_ekf));
  EXPECT_LE(ate(live_psm), 1.10 * ate(undisturbed_psm));
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}
