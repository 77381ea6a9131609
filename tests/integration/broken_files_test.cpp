// Broken files handed to the polarslam command (issue 16): every one gets a clear message and an
// exit status that says whether the command did its job; none crashes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "child_process.hpp"

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

}  // namespace
}  // namespace polarslam
