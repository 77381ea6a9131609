// Bad file inputs (issue 9): world, robot config and group YAML files and relations files with
// truncated, binary or absurd content each give one std::runtime_error naming the file and the
// line ("FILE:LINE: what"), never a crash or a silently accepted value.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "io/relations.hpp"
#include "io/tum.hpp"
#include "launch/group_file.hpp"
#include "robot/robot_description.hpp"
#include "sim/world.hpp"

namespace polarslam {
namespace {

namespace fs = std::filesystem;

class FileInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("polarslam-robustness-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& content) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }

  fs::path dir_;
};

/// Runs `load`, which must throw std::runtime_error whose message is "PATH:LINE: ..." with the
/// given line (0: any line number) and mentions `fragment`.
template <typename F>
void expectFileLineError(F&& load, const std::string& path, int line, const std::string& fragment) {
  try {
    load();
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    SCOPED_TRACE(what);
    ASSERT_EQ(what.rfind(path + ":", 0), 0u) << "message does not start with the file name";
    const std::string rest = what.substr(path.size() + 1);
    const size_t colon = rest.find(':');
    ASSERT_NE(colon, std::string::npos);
    const std::string number = rest.substr(0, colon);
    ASSERT_FALSE(number.empty());
    ASSERT_EQ(number.find_first_not_of("0123456789"), std::string::npos) << "no line number";
    if (line > 0) {
      EXPECT_EQ(std::stoi(number), line);
    }
    EXPECT_NE(what.find(fragment), std::string::npos) << "expected to mention '" << fragment << "'";
    return;
  } catch (const std::exception& e) {
    FAIL() << "wrong exception type: " << e.what();
  }
  FAIL() << "no error for " << path;
}

const std::string kWorld =
    "name: box\n"
    "walls:\n"
    "  - name: outer\n"
    "    closed: true\n"
    "    material: wall\n"
    "    points: [[-1, -1], [1, -1], [1, 1], [-1, 1]]\n"
    "start: {x: 0, y: 0, theta_deg: 0}\n"
    "path:\n"
    "  loop: false\n"
    "  waypoints: [[0, 0], [0.5, 0]]\n";

TEST_F(FileInputs, ValidWorldLoads) {
  const std::string path = write("world.yaml", kWorld);
  EXPECT_NO_THROW((void)loadWorld(path));
}

TEST_F(FileInputs, TruncatedWorld) {
  const std::string path = write("world.yaml", kWorld.substr(0, kWorld.find("[1, 1]")));
  expectFileLineError([&] { (void)loadWorld(path); }, path, 0, "YAML");
}

TEST_F(FileInputs, BinaryWorld) {
  std::string bytes = "name: box\nwalls:\n";
  for (int i = 0; i < 256; ++i) bytes += static_cast<char>((i * 37) & 0xff);
  const std::string path = write("world.yaml", bytes);
  expectFileLineError([&] { (void)loadWorld(path); }, path, 0, "");
}

TEST_F(FileInputs, AbsurdWorldCoordinate) {
  std::string text = kWorld;
  text.replace(text.find("[1, 1]"), 6, "[1e300, 1]");
  const std::string path = write("world.yaml", text);
  expectFileLineError([&] { (void)loadWorld(path); }, path, 6, "");
}

TEST_F(FileInputs, WorldWallIsNotASequence) {
  std::string text = kWorld;
  text.replace(text.find("[[-1, -1], [1, -1], [1, 1], [-1, 1]]"), 36, "banana");
  const std::string path = write("world.yaml", text);
  expectFileLineError([&] { (void)loadWorld(path); }, path, 6, "");
}

TEST_F(FileInputs, ValidRobotLoads) {
  const std::string path = write("robot.yaml", "robot:\n  wheel_base: 0.4\nlaser:\n  beams: 91\n");
  EXPECT_NO_THROW((void)loadRobotDescription(path));
}

TEST_F(FileInputs, TruncatedRobot) {
  const std::string path = write("robot.yaml", "robot:\n  wheel_base: 0.4\nlaser:\n  mount: {x: 0.2, y:");
  expectFileLineError([&] { (void)loadRobotDescription(path); }, path, 0, "YAML");
}

TEST_F(FileInputs, BinaryRobot) {
  const std::string path = write("robot.yaml", std::string("\x7f" "ELF\x02\x01\x01\0\0\0\0\0\0\0\0\0\x03\0>\0", 20));
  expectFileLineError([&] { (void)loadRobotDescription(path); }, path, 1, "");
}

TEST_F(FileInputs, AbsurdRobotValues) {
  const std::string beams = write("beams.yaml", "robot:\n  wheel_base: 0.4\nlaser:\n  beams: -5\n");
  expectFileLineError([&] { (void)loadRobotDescription(beams); }, beams, 4, "beams");
  const std::string rate = write("rate.yaml", "odometry:\n  rate: 1e308\n");
  expectFileLineError([&] { (void)loadRobotDescription(rate); }, rate, 2, "rate");
  const std::string nan = write("nan.yaml", "robot:\n  max_speed: .nan\n");
  expectFileLineError([&] { (void)loadRobotDescription(nan); }, nan, 2, "max_speed");
}

const std::string kGroup =
    "name: g\n"
    "commands:\n"
    "  - name: a\n"
    "    exec: /bin/true\n"
    "    args: [x]\n"
    "    stop_signal: SIGINT\n"
    "    stop_grace: 1\n";

TEST_F(FileInputs, ValidGroupLoads) {
  const std::string path = write("group.yaml", kGroup);
  EXPECT_NO_THROW((void)loadGroupFile(path, {}));
}

TEST_F(FileInputs, TruncatedGroup) {
  const std::string path = write("group.yaml", kGroup.substr(0, kGroup.find("x]")));
  expectFileLineError([&] { (void)loadGroupFile(path, {}); }, path, 0, "");
}

TEST_F(FileInputs, BinaryGroup) {
  std::string bytes = kGroup;
  bytes += std::string("  - name: b\n    exec: \x01\x02\xff\xfe\0\0\x80\n", 29);
  const std::string path = write("group.yaml", bytes);
  expectFileLineError([&] { (void)loadGroupFile(path, {}); }, path, 0, "");
}

TEST_F(FileInputs, AbsurdGroupValues) {
  std::string signal = kGroup;
  signal.replace(signal.find("SIGINT"), 6, "SIGBANANA");
  const std::string signal_path = write("signal.yaml", signal);
  expectFileLineError([&] { (void)loadGroupFile(signal_path, {}); }, signal_path, 6, "expected a signal");
  std::string grace = kGroup;
  grace.replace(grace.find("stop_grace: 1"), 13, "stop_grace: -1e300");
  const std::string grace_path = write("grace.yaml", grace);
  expectFileLineError([&] { (void)loadGroupFile(grace_path, {}); }, grace_path, 7, "stop_grace");
}

TEST_F(FileInputs, RelationsTruncatedBinaryAbsurd) {
  const std::string good = "1.0 2.0 0.5 0 0 0 0 0.1\n";
  EXPECT_EQ(parseRelations(good, "r.txt").size(), 1u);
  const std::string truncated = write("truncated.txt", good + "2.0 3.0 0.5 0");
  expectFileLineError([&] { (void)readRelations(truncated); }, truncated, 2, "expected 8 fields");
  const std::string binary = write("binary.txt", good + std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16));
  // Bytes >= 0x80 may be UTF-8: the first control byte (0x1a) is on line 3, after the PNG CR LF.
  expectFileLineError([&] { (void)readRelations(binary); }, binary, 3, "binary content");
  const std::string absurd = write("absurd.txt", good + good + "1e300 2 0 0 0 0 0 0\n");
  expectFileLineError([&] { (void)readRelations(absurd); }, absurd, 3, "t1");
  const std::string nan = write("nan.txt", "1 2 nan 0 0 0 0 0\n");
  expectFileLineError([&] { (void)readRelations(nan); }, nan, 1, "bad x");
}

TEST_F(FileInputs, TumTruncatedAndBinary) {
  const std::string good = "1700000000.0 0 0 0 0 0 0 1\n";
  const std::string truncated = write("traj.tum", good + "1700000000.1 0.05 0");
  expectFileLineError([&] { (void)readTumTrajectory(truncated); }, truncated, 2, "");
  const std::string binary = write("bin.tum", good + good + std::string("\0\0\xff", 3));
  expectFileLineError([&] { (void)readTumTrajectory(binary); }, binary, 3, "binary content");
}

}  // namespace
}  // namespace polarslam
