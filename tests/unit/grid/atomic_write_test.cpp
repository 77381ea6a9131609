// A writer killed at any moment never leaves a partial map file: each name holds either nothing
// or a complete file (temp file + rename).
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <random>
#include <thread>

#include "grid/grid_files.hpp"
#include "grid_fixtures.hpp"

namespace polarslam {
namespace {

const char* const kNames[] = {"map.ot", "map.bt", "map.pgm", "map.yaml", "map.png"};

std::string freshDir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam_atomic_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

TEST(AtomicGridFiles, KilledWriterLeavesOnlyCompleteFiles) {
  const OccupancyGrid grid = test::twoRoomGrid(0.02);  // fine cells: files big enough to be caught mid-write
  const std::string reference = freshDir("reference");
  const auto start = std::chrono::steady_clock::now();
  writeGridFiles(reference, grid);
  // Kill times spread over about two whole writes, so kills land in every file's write.
  const auto write_us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start);
  std::map<std::string, uintmax_t> full_size;
  for (const char* name : kNames) full_size[name] = std::filesystem::file_size(std::filesystem::path(reference) / name);

  const std::string dir = freshDir("killed");
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> delay_us(0, 2 * write_us.count());
  int complete_seen = 0;
  for (int round = 0; round < 10; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      try {
        for (;;) writeGridFiles(dir, grid);  // until killed
      } catch (...) {
      }
      ::_exit(1);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng)));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    for (const char* name : kNames) {
      const auto path = std::filesystem::path(dir) / name;
      if (!std::filesystem::exists(path)) continue;
      EXPECT_EQ(std::filesystem::file_size(path), full_size[name]) << name << " is partial after round " << round;
      ++complete_seen;
    }
    octomap::OcTree bt(0.1);
    if (std::filesystem::exists(std::filesystem::path(dir) / "map.bt")) {
      EXPECT_TRUE(bt.readBinary((std::filesystem::path(dir) / "map.bt").string()));
    }
  }
  EXPECT_GT(complete_seen, 0);
  std::filesystem::remove_all(dir);
  std::filesystem::remove_all(reference);
}

TEST(AtomicGridFiles, FailedWriteLeavesThePreviousFileIntact) {
  const OccupancyGrid grid = test::twoRoomGrid();
  const std::string dir = freshDir("failed");
  writeGridFiles(dir, grid);
  const auto bt = std::filesystem::path(dir) / "map.bt";
  const uintmax_t size = std::filesystem::file_size(bt);
  // A directory where the temp file must go makes the next write fail.
  std::filesystem::create_directories(bt.string() + ".tmp");
  EXPECT_THROW(writeGridFiles(dir, OccupancyGrid()), std::runtime_error);
  EXPECT_EQ(std::filesystem::file_size(bt), size);
  octomap::OcTree tree(0.1);
  EXPECT_TRUE(tree.readBinary(bt.string()));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace polarslam
