// LcmLogReader and LcmLogWriter on broken files: not a log, empty, torn at the end, corrupt in
// the middle (issue 16, item 2); a writer that fails leaves nothing under the final name (item 3).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/lcm_log.hpp"

namespace polarslam {
namespace {

namespace fs = std::filesystem;

class LcmLogFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("polarslam-lcm-log-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A log of `events` events on channel "A", 100 bytes of data each; returns its bytes.
  std::string writeLog(const std::string& name, int events) {
    const std::string path = (dir_ / name).string();
    LcmLogWriter writer(path);
    const std::vector<uint8_t> data(100, 7);
    for (int i = 0; i < events; ++i) writer.writeRaw("A", 1000 + i, data.data(), data.size());
    writer.close();
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
  std::string put(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  static long readAll(LcmLogReader& reader) {
    LogEvent event;
    long n = 0;
    while (reader.next(event)) ++n;
    return n;
  }
  static std::string errorOpening(const std::string& path) {
    try {
      LcmLogReader reader(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(LcmLogFiles, AnIntactLogReadsBackWithoutWarnings) {
  writeLog("good.lcmlog", 10);
  LcmLogReader reader((dir_ / "good.lcmlog").string());
  LogEvent event;
  ASSERT_TRUE(reader.next(event));
  EXPECT_EQ(event.channel, "A");
  EXPECT_EQ(event.utime, 1000);
  EXPECT_EQ(event.data.size(), 100u);
  EXPECT_EQ(readAll(reader), 9);
  EXPECT_TRUE(reader.warnings().empty());
  EXPECT_DOUBLE_EQ(reader.progress(), 1.0);
}

TEST_F(LcmLogFiles, RandomBytesEmptyAndTinyFilesAreNotLogs) {
  std::string random(4096, '\0');
  for (size_t i = 0; i < random.size(); ++i) random[i] = static_cast<char>((i * 2654435761u) >> 13);
  EXPECT_NE(errorOpening(put("random.bin", random)).find("is not an LCM log"), std::string::npos);
  EXPECT_NE(errorOpening(put("empty.lcmlog", "")).find("is empty, not an LCM log"), std::string::npos);
  EXPECT_NE(errorOpening(put("tiny2.lcmlog", "twenty bytes of text")).find("tiny2.lcmlog' is not an LCM log"),
            std::string::npos);
}

TEST_F(LcmLogFiles, ATornLastEventIsAWarningWithItsOffsetAndTheEventsBeforeIt) {
  const std::string log = writeLog("full.lcmlog", 10);
  const size_t event_bytes = log.size() / 10;
  const std::string path = put("torn.lcmlog", log.substr(0, log.size() - 30));
  LcmLogReader reader(path);
  EXPECT_EQ(readAll(reader), 9);
  ASSERT_EQ(reader.warnings().size(), 1u);
  EXPECT_NE(reader.warnings()[0].find("truncated at byte " + std::to_string(9 * event_bytes) + " after 9 events"),
            std::string::npos)
      << reader.warnings()[0];
}

TEST_F(LcmLogFiles, ACorruptLengthInTheMiddleIsSkippedToTheNextEventAndNamed) {
  std::string log = writeLog("full.lcmlog", 10);
  const size_t event_bytes = log.size() / 10;
  const size_t fourth = 3 * event_bytes;
  log[fourth + 24] = '\x7f';  // the data length of the fourth event: 2 GB
  LcmLogReader reader(put("corrupt.lcmlog", log));
  EXPECT_EQ(readAll(reader), 9) << "only the corrupt event is lost";
  ASSERT_EQ(reader.warnings().size(), 1u);
  EXPECT_NE(reader.warnings()[0].find("corrupt event at byte " + std::to_string(fourth) + " (after 3 events)"),
            std::string::npos)
      << reader.warnings()[0];
}

TEST_F(LcmLogFiles, AWriterThatDoesNotFinishLeavesNoFileUnderTheFinalName) {
  const std::string path = (dir_ / "unfinished.lcmlog").string();
  {
    LcmLogWriter writer(path);
    const uint8_t byte = 1;
    writer.writeRaw("A", 1, &byte, 1);
  }  // destroyed without close(): an exception left the command
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST_F(LcmLogFiles, AFullDiskIsAnErrorAndLeavesNoFile) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  // The writer writes to path + ".tmp": make that name the full device.
  const std::string path = (dir_ / "full-disk.lcmlog").string();
  fs::create_symlink("/dev/full", path + ".tmp");
  LcmLogWriter writer(path);
  const std::vector<uint8_t> data(1 << 16, 1);
  EXPECT_THROW(
      {
        for (int i = 0; i < 64; ++i) writer.writeRaw("A", i, data.data(), data.size());
        writer.close();
      },
      std::runtime_error);
  EXPECT_FALSE(fs::exists(path)) << "a truncated log appeared under the final name";
}

}  // namespace
}  // namespace polarslam
