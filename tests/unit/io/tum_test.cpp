#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "io/text_fields.hpp"
#include "io/tum.hpp"

namespace polarslam {
namespace {

namespace fs = std::filesystem;

fs::path freshDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("polarslam_eval_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string tumErrorOf(const std::string& text) {
  try {
    parseTumTrajectory(text, "traj.tum");
  } catch (const TextFormatError& e) {
    return e.what();
  }
  return "";
}

TEST(Tum, RoundTripKeepsMicrosecondsAndYawOverTheWholeCircle) {
  std::vector<PoseStamped> poses;
  const int64_t unix_time = 1134864645903210;  // MIT CSAIL's time base, µs
  for (int i = 0; i <= 40; ++i) {
    PoseStamped p;
    p.utime = unix_time + i * 123457;
    p.pose = Pose2(-3.0 + 0.37 * i, 12.5 - 0.011 * i, wrapAngle(-std::numbers::pi + i * std::numbers::pi / 20.0));
    poses.push_back(p);
  }
  poses[0].pose.theta = std::numbers::pi;  // the boundary of (−π, π]
  const fs::path file = freshDir("tum") / "trajectory.tum";
  writeTumTrajectory(file.string(), poses);
  const std::vector<PoseStamped> back = readTumTrajectory(file.string());
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(back[i].utime, poses[i].utime);
    EXPECT_NEAR(back[i].pose.x, poses[i].pose.x, 1e-9);
    EXPECT_NEAR(back[i].pose.y, poses[i].pose.y, 1e-9);
    EXPECT_NEAR(wrapAngle(back[i].pose.theta - poses[i].pose.theta), 0.0, 1e-8) << i;
  }
  EXPECT_FALSE(fs::exists(file.string() + ".tmp"));
}

TEST(Tum, WritesTheColumnsEvoExpects) {
  PoseStamped p;
  p.utime = 1500000;
  p.pose = Pose2(1.0, 2.0, std::numbers::pi / 2);
  const std::string text = formatTumTrajectory({p});
  EXPECT_EQ(text, "# t x y z qx qy qz qw\n1.500000 1.000000000 2.000000000 0.000000000 0.000000000 0.000000000 "
                  "0.707106781 0.707106781\n");
}

TEST(Tum, ReadsScientificTimestampsCommentsAndUnnormalisedQuaternions) {
  const std::string text =
      "# written by numpy.savetxt\n"
      "\n"
      "1.134864645903210e+09 1 2 0.5 0 0 0.5 0.5\n"
      "  12.25\t-1 -2 0 0 0 0 -1\r\n";
  const std::vector<PoseStamped> poses = parseTumTrajectory(text, "evo.tum");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].utime, 1134864645903210);
  EXPECT_NEAR(poses[0].pose.theta, std::numbers::pi / 2, 1e-12);
  EXPECT_EQ(poses[1].utime, 12250000);
  EXPECT_NEAR(poses[1].pose.theta, 0.0, 1e-12);  // q = −1 is the identity rotation
  EXPECT_DOUBLE_EQ(poses[1].pose.y, -2.0);
}

TEST(Tum, MalformedLinesNameFileAndLine) {
  EXPECT_EQ(tumErrorOf("0 0 0 0 0 0 0 1\n1 2 3\n"), "traj.tum:2: expected 8 fields 't x y z qx qy qz qw', found 3");
  EXPECT_EQ(tumErrorOf("# c\n0 0 nan 0 0 0 0 1\n"), "traj.tum:2: bad y 'nan'");
  EXPECT_EQ(tumErrorOf("abc 0 0 0 0 0 0 1\n"), "traj.tum:1: bad timestamp 'abc'");
  EXPECT_EQ(tumErrorOf("0 0 0 0 0 0 0 0\n"), "traj.tum:1: quaternion has zero length");
  EXPECT_NE(tumErrorOf(std::string("0 0 0 0 0 0 0 1\n0 0") + '\0' + " 0").find("traj.tum:2: binary content"),
            std::string::npos);
}

TEST(Tum, RefusesToWriteNonFinitePosesAndLeavesTheOldFile) {
  const fs::path file = freshDir("tum_nan") / "t.tum";
  writeText(file, "old\n");
  PoseStamped bad;
  bad.pose.x = std::nan("");
  EXPECT_THROW(writeTumTrajectory(file.string(), {bad}), std::invalid_argument);
  std::ifstream in(file);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "old");
}

TEST(Tum, MissingFileIsAClearError) {
  try {
    readTumTrajectory("/nonexistent/dir/t.tum");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/t.tum"), std::string::npos);
  }
}

TEST(TextFields, DecimalSecondsConvertExactlyAndRound) {
  EXPECT_EQ(parseSecondsAsUtime("1134864645.90321"), 1134864645903210);
  EXPECT_EQ(parseSecondsAsUtime("0.0000005"), 1);
  EXPECT_EQ(parseSecondsAsUtime("0.0000004"), 0);
  EXPECT_EQ(parseSecondsAsUtime("-1.5"), -1500000);
  EXPECT_EQ(parseSecondsAsUtime(".5"), 500000);
  EXPECT_EQ(parseSecondsAsUtime("3"), 3000000);
  EXPECT_EQ(parseSecondsAsUtime("1e3"), 1000000000);
  EXPECT_FALSE(parseSecondsAsUtime("1.2.3"));
  EXPECT_FALSE(parseSecondsAsUtime("."));
  EXPECT_FALSE(parseSecondsAsUtime("inf"));
  EXPECT_EQ(formatUtimeAsSeconds(-1500000), "-1.500000");
  EXPECT_EQ(formatUtimeAsSeconds(7), "0.000007");
  EXPECT_EQ(formatUtimeAsSeconds(1134864645903210), "1134864645.903210");
}

}  // namespace
}  // namespace polarslam
