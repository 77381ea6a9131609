// Output lines of supervised processes, and finding their executables.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "launch/executable_search.hpp"
#include "launch/line_splitter.hpp"

namespace polarslam {
namespace {

using Lines = std::vector<std::string>;

TEST(LineSplitter, SplitsAcrossChunksAndKeepsTheUnfinishedLine) {
  LineSplitter s;
  auto feed = [&](const std::string& chunk) { return s.feed(chunk.data(), chunk.size()); };
  EXPECT_EQ(feed("one\ntw"), Lines{"one"});
  EXPECT_EQ(feed("o\r\n\nthr"), (Lines{"two", ""}));
  EXPECT_EQ(feed("ee"), Lines{});
  EXPECT_EQ(s.finish(), Lines{"three"});
  EXPECT_EQ(s.finish(), Lines{});
}

TEST(LineSplitter, CutsOverlongLines) {
  LineSplitter s(4);
  EXPECT_EQ(s.feed("abcdefghij\n", 11), (Lines{"abcd", "efgh", "ij"}));
}

TEST(ExecutableSearch, FindsProgramsOnThePathOrRelativeToTheWorkingDir) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-exe-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir / "bin");
  const auto tool = dir / "bin" / "tool";
  std::ofstream(tool) << "#!/bin/sh\n";
  const auto plain = dir / "bin" / "not-executable";
  std::ofstream(plain) << "data\n";
  std::filesystem::permissions(tool, std::filesystem::perms::owner_all);

  const std::string path = "/nonexistent:" + (dir / "bin").string();
  EXPECT_EQ(findExecutable("tool", path, ""), tool.string());
  EXPECT_EQ(findExecutable("tool", "bin", dir.string()), tool.string());
  EXPECT_EQ(findExecutable("./bin/tool", "", dir.string()), tool.string());
  EXPECT_EQ(findExecutable(tool.string(), "", "/"), tool.string());
  EXPECT_EQ(findExecutable("not-executable", path, ""), "");
  EXPECT_EQ(findExecutable("bin", "", dir.string()), "");  // a folder is not a program
  EXPECT_EQ(findExecutable("polarslam-no-such-program", path, ""), "");
  EXPECT_EQ(findExecutable("", path, ""), "");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace polarslam
