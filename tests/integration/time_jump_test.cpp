// One message stamped an hour in the future (issue 16, item 1) must not become anyone's clock:
// offline, both SLAMs finish with the error of the clean log; live, polarslam-ekf-slam rejects
// that one message, keeps handling the odometry after it, and keeps it out of its journal.
// A ground-truth pose of 1e296 m is rejected, not scored as "ATE inf".
#include <gtest/gtest.h>
#include <signal.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <thread>

#include "child_process.hpp"
#include "common/lcm_log.hpp"
#include "common/process_context.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::freshDir;
using polarslam::testing::readFile;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;

namespace {

namespace fs = std::filesystem;
constexpr int64_t kHour = 3600LL * 1000000;

/// The log with, a third of the way in, a copy of an ODOMETRY message stamped an hour later and
/// a GROUND_TRUTH pose 1e296 m away.
void writeWithTimeJump(const std::string& clean, const std::string& out) {
  polarslam::LcmLogReader reader(clean);
  polarslam::LcmLogWriter writer(out);
  polarslam::LogEvent event;
  long odometry = 0;
  while (reader.next(event)) {
    writer.writeRaw(event.channel, event.utime, event.data.data(), event.data.size());
    if (event.channel != "ODOMETRY" || ++odometry != 100) continue;
    polarslam::odometry_t future;
    ASSERT_TRUE(event.decode(future));
    future.utime += kHour;
    writer.write("ODOMETRY", event.utime, future);
    polarslam::pose_t absurd{};
    absurd.utime = future.utime - kHour;
    absurd.x = 1e296;
    writer.write("GROUND_TRUTH", event.utime, absurd);
  }
  writer.close();
}

nlohmann::json runReport(const std::string& log, const std::string& pipeline, const fs::path& out) {
  const int code = runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", pipeline, "-o", out.string()},
                            out.string() + ".out", 240s);
  EXPECT_EQ(code, 0) << pipeline << " on " << log << ": " << readFile(out.string() + ".out");
  return nlohmann::json::parse(readFile(out / "report.json"), nullptr, false);
}

bool rejectedFor(const nlohmann::json& report, const std::string& words) {
  if (!report.contains("rejected")) return false;
  for (const auto& [why, count] : report["rejected"].items())
    if (why.find(words) != std::string::npos && count.get<long>() >= 1) return true;
  return false;
}

}  // namespace

TEST(TimeJump, OneFutureStampedOdometryLeavesBothOfflineSlamsAsAccurateAsTheCleanLog) {
  const fs::path dir = freshDir("time-jump-offline");
  const std::string clean = (dir / "clean.lcmlog").string(), jumped = (dir / "jumped.lcmlog").string();
  ASSERT_EQ(runToEnd({binPath("polarslam"), "simulate", "--world", sourcePath("config/worlds/office.yaml"), "--seconds",
                      "40", "-o", clean},
                     dir / "simulate.out", 120s),
            0)
      << readFile(dir / "simulate.out");
  writeWithTimeJump(clean, jumped);
  for (const std::string pipeline : {"ekf", "psm-slam"}) {
    const nlohmann::json good = runReport(clean, pipeline, dir / (pipeline + "-clean"));
    const nlohmann::json bad = runReport(jumped, pipeline, dir / (pipeline + "-jumped"));
    ASSERT_TRUE(good.contains("ate_rmse_m") && bad.contains("ate_rmse_m")) << pipeline;
    const double clean_ate = good["ate_rmse_m"].get<double>(), jumped_ate = bad["ate_rmse_m"].get<double>();
    EXPECT_NEAR(jumped_ate, clean_ate, 0.1 * clean_ate + 0.002) << pipeline;
    EXPECT_TRUE(rejectedFor(bad, "ODOMETRY: time stamp jumps")) << bad["rejected"].dump();
    EXPECT_TRUE(rejectedFor(bad, "pose: absurd position")) << bad["rejected"].dump();
    EXPECT_EQ(bad["trajectory_poses"], good["trajectory_poses"]) << pipeline;
  }
  if (!HasFailure()) fs::remove_all(dir);
}

TEST(TimeJump, LiveEkfSlamRejectsTheFutureMessageKeepsGoingAndKeepsItOutOfTheJournal) {
  lcm::LCM lcm(polarslam::resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const fs::path dir = freshDir("time-jump-live");
  const std::string journal = (dir / "ekf-slam.journal").string();
  polarslam::testing::ChildProcess slam({binPath("polarslam-ekf-slam"), "--journal", journal},
                                        (dir / "ekf-slam.log").string());
  polarslam::process_status_t status{};
  struct StatusWatch {
    polarslam::process_status_t* status;
    void on(const lcm::ReceiveBuffer*, const std::string&, const polarslam::process_status_t* m) {
      if (m->name == "polarslam-ekf-slam") *status = *m;
    }
  } watch{&status};
  lcm.subscribe("PROCESS_STATUS", &StatusWatch::on, &watch);
  std::this_thread::sleep_for(1500ms);

  const int64_t t0 = 1'700'000'000'000'000;
  for (int i = 0; i < 60; ++i) {
    polarslam::odometry_t m{};
    m.utime = t0 + i * 100000 + (i == 30 ? kHour : 0);
    m.seq = i;
    m.x = 0.01 * i;
    for (int k = 0; k < 9; k += 4) m.cov[k] = 1e-4;
    lcm.publish("ODOMETRY", &m);
    std::this_thread::sleep_for(5ms);
  }
  std::this_thread::sleep_for(500ms);
  slam.signal(SIGINT);
  ASSERT_TRUE(slam.waitFor(15s));
  EXPECT_EQ(slam.exitCode(), 0);
  for (auto end = std::chrono::steady_clock::now() + 300ms; std::chrono::steady_clock::now() < end;) lcm.handleTimeout(20);
  EXPECT_EQ(status.messages_rejected, 1) << readFile(dir / "ekf-slam.log");
  EXPECT_EQ(status.messages_handled, 59) << "the odometry after the future one is not 'time went backwards'";
  EXPECT_EQ(status.messages_dropped, 0) << "the rejected message was counted again as a sequence gap";

  polarslam::LcmLogReader reader(journal);
  polarslam::LogEvent event;
  long journaled = 0;
  while (reader.next(event)) {
    polarslam::odometry_t m;
    if (event.channel != "ODOMETRY" || !event.decode(m)) continue;
    ++journaled;
    EXPECT_LT(m.utime, t0 + kHour) << "the rejected message went into the journal";
  }
  EXPECT_EQ(journaled, 59);
  if (!HasFailure()) fs::remove_all(dir);
}
