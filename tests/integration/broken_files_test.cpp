// Broken files handed to the polarslam command (issue 16): every one gets a clear message and an
// exit status that says whether the command did its job; none crashes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "common/lcm_log.hpp"

namespace polarslam {
namespace {

using namespace std::chrono_literals;
using ::polarslam::testing::binPath;
using ::polarslam::testing::readFile;
using ::polarslam::testing::runToEnd;
using ::polarslam::testing::sourcePath;

class BrokenFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("polarslam-broken-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& content) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }
  /// Runs `polarslam args...`; returns the exit status and leaves the output in `output`.
  int polarslam(std::vector<std::string> args, std::string& output) {
    args.insert(args.begin(), binPath("polarslam"));
    const auto out = dir_ / "command.out";
    const int rc = runToEnd(args, out, 120s);
    output = readFile(out.string());
    return rc;
  }

  std::filesystem::path dir_;
};

TEST_F(BrokenFiles, AFileThatIsNotAnLcmLogIsRefusedByName) {
  const std::string junk = write("junk.bin", std::string(4096, '\x5a'));
  std::string out;
  EXPECT_EQ(polarslam({"run", "--log", junk, "-o", (dir_ / "run").string()}, out), 1);
  EXPECT_NE(out.find("is not an LCM log"), std::string::npos) << out;
  const std::string empty = write("empty.bin", "");
  EXPECT_EQ(polarslam({"log-info", "--log", empty}, out), 1);
  EXPECT_NE(out.find("is empty"), std::string::npos) << out;
}

TEST_F(BrokenFiles, ATornLogRunsUpToItsLastWholeEventAndTheReportSaysSo) {
  const std::string whole = readFile(sourcePath("logs/office.lcmlog"));
  ASSERT_GT(whole.size(), 400000u);
  const std::string torn = write("torn.lcmlog", whole.substr(0, 400000 - 7));
  std::string out;
  const auto run_dir = dir_ / "run";
  ASSERT_EQ(polarslam({"run", "--log", torn, "-o", run_dir.string()}, out), 0) << out;
  EXPECT_NE(out.find("truncated at byte"), std::string::npos) << out;
  EXPECT_NE(readFile((run_dir / "report.json").string()).find("truncated at byte"), std::string::npos);
}

TEST_F(BrokenFiles, AnImportWithoutOneUsableLaserLineFails) {
  const std::string carmen = write("bad.log",
                                   "ODOM 0.5 0.25 0.1 0.2 0.0 0.0 99.0 host 99.1\n"
                                   "FLASER 181 1 2 3\n"
                                   "FLASER 3 1e309 2 2 0 0 0 0 0 0 100.0 host 100.1\n");
  std::string out;
  EXPECT_EQ(polarslam({"import", carmen, "-o", (dir_ / "bad.lcmlog").string()}, out), 1);
  EXPECT_NE(out.find("holds no usable laser line"), std::string::npos) << out;
  EXPECT_NE(out.find("bad.log:2:"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.lcmlog"));
}

TEST_F(BrokenFiles, ALaserPipelineWithoutLaserDataWarnsOrFailsWhenStrict) {
  LcmLogReader reader(sourcePath("logs/office.lcmlog"));
  const std::string no_laser = (dir_ / "no-laser.lcmlog").string();
  LcmLogWriter writer(no_laser);
  LogEvent event;
  while (reader.next(event))
    if (event.channel != "LASER") writer.writeRaw(event.channel, event.utime, event.data.data(), event.data.size());
  writer.close();
  std::string out;
  ASSERT_EQ(polarslam({"run", "--log", no_laser, "--pipeline", "psm-slam", "-o", (dir_ / "run").string()}, out), 0) << out;
  EXPECT_NE(out.find("warning: run psm-slam: the log has no LASER message"), std::string::npos) << out;
  EXPECT_NE(readFile((dir_ / "run" / "report.json").string()).find("odometry only"), std::string::npos);
  EXPECT_EQ(polarslam({"run", "--log", no_laser, "--pipeline", "psm-slam", "--strict", "-o", (dir_ / "strict").string()}, out), 1);
  EXPECT_NE(out.find("(--strict)"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "strict"));
}

TEST_F(BrokenFiles, ALogRecordedBackwardsHasAPositiveRealTimeFactor) {
  LcmLogReader reader(sourcePath("logs/office.lcmlog"));
  std::vector<LogEvent> events;
  LogEvent event;
  while (reader.next(event) && events.size() < 3000) events.push_back(event);
  const std::string reversed = (dir_ / "reversed.lcmlog").string();
  LcmLogWriter writer(reversed);
  for (auto e = events.rbegin(); e != events.rend(); ++e) writer.writeRaw(e->channel, e->utime, e->data.data(), e->data.size());
  writer.close();
  std::string out;
  ASSERT_EQ(polarslam({"run", "--log", reversed, "-o", (dir_ / "run").string()}, out), 0) << out;
  const std::string report = readFile((dir_ / "run" / "report.json").string());
  EXPECT_EQ(report.find("\"realtime_factor\": -"), std::string::npos) << report;
  EXPECT_NE(report.find("\"realtime_factor\": "), std::string::npos) << report;
}

TEST_F(BrokenFiles, AStoppedRunLeavesNoFolderAndARerunReplacesTheOldOne) {
  const auto out_dir = dir_ / "run";
  std::filesystem::create_directories(out_dir);
  std::ofstream(out_dir / "from-an-older-run.txt") << "stale\n";
  std::string out;
  ASSERT_EQ(polarslam({"run", "--log", sourcePath("logs/office.lcmlog"), "--pipeline", "psm-slam", "-o", out_dir.string()},
                      out),
            0)
      << out;
  EXPECT_TRUE(std::filesystem::exists(out_dir / "report.json"));
  EXPECT_FALSE(std::filesystem::exists(out_dir / "from-an-older-run.txt")) << "two runs' files mixed";
  // Not on a terminal: no progress bar redrawn with '\r', and nothing of liboctomap's debug output.
  EXPECT_EQ(out.find('\r'), std::string::npos) << out;
  EXPECT_EQ(out.find(" done."), std::string::npos) << out;

  const auto stopped = dir_ / "stopped";
  ::polarslam::testing::ChildProcess run({binPath("polarslam"), "run", "--log", sourcePath("logs/office.lcmlog"),
                                          "--pipeline", "psm-slam", "-o", stopped.string()},
                                         (dir_ / "stopped.out").string());
  const auto work = dir_ / "stopped.incomplete";
  for (int i = 0; i < 2000 && !std::filesystem::exists(work); ++i) std::this_thread::sleep_for(1ms);
  ASSERT_TRUE(std::filesystem::exists(work)) << "the run never started";
  run.signal(SIGTERM);
  ASSERT_TRUE(run.waitFor(60s));
  EXPECT_EQ(run.exitCode(), 1);
  EXPECT_NE(readFile(dir_ / "stopped.out").find("stopped by SIGTERM"), std::string::npos) << readFile(dir_ / "stopped.out");
  EXPECT_FALSE(std::filesystem::exists(stopped));
  EXPECT_FALSE(std::filesystem::exists(work));
}

}  // namespace
}  // namespace polarslam
