// InputJournal: a journal resumes its own launch and refuses another launch's (issue 16, item 5).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "common/input_journal.hpp"

namespace polarslam {
namespace {

using namespace std::chrono_literals;

class InputJournalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("polarslam-journal-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "stage.journal").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// One launch's process: recovers, then journals `count` messages.
  std::vector<LogEvent> runLaunch(const std::string& launch, int count, std::string* refused = nullptr) {
    InputJournal journal(path_, 0ms, launch);
    std::vector<LogEvent> recovered = journal.recover();
    if (refused) *refused = journal.refused();
    for (int i = 0; i < count; ++i) {
      const std::string payload = launch + "#" + std::to_string(i);
      journal.append("ODOMETRY", 1000 + i, payload.data(), payload.size());
    }
    journal.flushIfDue();
    return recovered;
  }

  std::filesystem::path dir_;
  std::string path_;
};

TEST_F(InputJournalTest, ARestartInTheSameLaunchReplaysEverything) {
  EXPECT_TRUE(runLaunch("host-1-100", 3).empty());
  const std::vector<LogEvent> replayed = runLaunch("host-1-100", 2);
  ASSERT_EQ(replayed.size(), 3u);
  EXPECT_EQ(std::string(replayed[2].data.begin(), replayed[2].data.end()), "host-1-100#2");
  EXPECT_EQ(runLaunch("host-1-100", 0).size(), 5u);
}

TEST_F(InputJournalTest, AnotherLaunchsJournalIsRefusedKeptAsideAndTheNewLaunchStartsEmpty) {
  runLaunch("host-1-100", 3);
  std::string refused;
  EXPECT_TRUE(runLaunch("host-2-200", 1, &refused).empty());
  EXPECT_NE(refused.find("belongs to launch 'host-1-100'"), std::string::npos) << refused;
  EXPECT_NE(refused.find("stale"), std::string::npos) << refused;
  EXPECT_TRUE(std::filesystem::exists(path_ + ".stale"));
  const std::vector<LogEvent> replayed = runLaunch("host-2-200", 0);
  ASSERT_EQ(replayed.size(), 1u) << "only the new launch's own message";
  EXPECT_EQ(std::string(replayed[0].data.begin(), replayed[0].data.end()), "host-2-200#0");
}

TEST_F(InputJournalTest, HandStartedProcessesResumeTheirOwnButNotALaunchersJournal) {
  runLaunch("", 2);
  EXPECT_EQ(runLaunch("", 0).size(), 2u);
  std::filesystem::remove(path_);
  runLaunch("host-1-100", 2);
  std::string refused;
  EXPECT_TRUE(runLaunch("", 0, &refused).empty());
  EXPECT_NE(refused.find("(started by hand)"), std::string::npos) << refused;
}

// A process killed with SIGKILL right after handling a message: with the default options the
// message is in the journal (the kernel has it), whatever the time since the last flush.
TEST_F(InputJournalTest, WithTheDefaultOptionsAKillNineRightAfterAMessageLosesNothing) {
  runLaunch("host-1-100", 1);
  const JournalOptions defaults;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    InputJournal journal(path_, std::chrono::milliseconds(static_cast<int64_t>(defaults.flush_period * 1000)),
                         "host-1-100");
    journal.recover();
    for (int i = 0; i < 4; ++i) {
      const std::string payload = "handled#" + std::to_string(i);
      journal.append("ODOMETRY", 2000 + i, payload.data(), payload.size());
      journal.flushIfDue();  // what ProcessContext::run does after each message
    }
    raise(SIGKILL);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  const std::vector<LogEvent> replayed = runLaunch("host-1-100", 0);
  ASSERT_EQ(replayed.size(), 5u) << "the earlier message and all four handled before the kill";
  EXPECT_EQ(std::string(replayed[4].data.begin(), replayed[4].data.end()), "handled#3");
}

}  // namespace
}  // namespace polarslam
