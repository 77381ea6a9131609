// CARMEN log parsing (docs/algorithms.md §20.2–§20.3, data README).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "io/carmen.hpp"

namespace polarslam {
namespace {

std::string flaserLine(int beams, double range, const std::string& stamp, double odom_x = 1.0) {
  std::ostringstream s;
  s << "FLASER " << beams;
  for (int i = 0; i < beams; ++i) s << " " << range;
  s << " 9.0 9.0 0.5 " << odom_x << " 2.0 0.25 " << stamp << " host 12.5";
  return s.str();
}

CarmenLog parse(const std::string& text, const CarmenOptions& options = {}) {
  std::istringstream in(text);
  return readCarmenLog(in, options);
}

TEST(Carmen, FlaserGivesOdometryThenScanWithExactTimestamp) {
  const CarmenLog log = parse(flaserLine(181, 2.5, "1134864645.903210") + "\n");
  ASSERT_EQ(log.events.size(), 2u);
  ASSERT_FALSE(log.events[0].isLaser());
  ASSERT_TRUE(log.events[1].isLaser());
  const OdometryReading& odo = log.events[0].odometry();
  EXPECT_EQ(odo.utime, 1134864645903210);
  EXPECT_DOUBLE_EQ(odo.pose.x, 1.0);  // the second (odometry) triple, not the laser pose
  EXPECT_DOUBLE_EQ(odo.pose.y, 2.0);
  EXPECT_DOUBLE_EQ(odo.pose.theta, 0.25);
  const LaserScan& scan = log.events[1].laser();
  EXPECT_EQ(scan.utime, 1134864645903210);
  EXPECT_EQ(scan.size(), 181u);
  EXPECT_FLOAT_EQ(scan.ranges[0], 2.5f);
  EXPECT_EQ(log.events[1].line, 1);
  EXPECT_EQ(log.flaser_lines, 1);
  EXPECT_EQ(log.malformed_count, 0);
}

TEST(Carmen, BearingGridFromTheBeamCount) {
  const double deg = std::numbers::pi / 180.0;
  struct Case { int beams; double first, last; };
  for (const Case c : {Case{180, -90.0, 89.0}, Case{181, -90.0, 90.0}, Case{360, -90.0, 89.5}, Case{361, -90.0, 90.0}}) {
    const CarmenLog log = parse(flaserLine(c.beams, 1.0, "10.0") + "\n");
    ASSERT_EQ(log.laserCount(), 1) << c.beams;
    const LaserScan& s = log.events[1].laser();
    EXPECT_NEAR(s.bearing(0), c.first * deg, 1e-12) << c.beams;
    EXPECT_NEAR(s.bearing(s.size() - 1), c.last * deg, 1e-9) << c.beams;
    EXPECT_EQ(log.unusual_beam_counts, 0);
  }
  const CarmenLog odd = parse(flaserLine(241, 1.0, "10.0") + "\n");
  EXPECT_EQ(odd.unusual_beam_counts, 1);
  EXPECT_NEAR(odd.events[1].laser().bearing(240), 90.0 * deg, 1e-9);
}

TEST(Carmen, NoReturnRangesAreBeyondRangeMax) {
  std::string line = flaserLine(180, 3.0, "10.0");
  line.replace(line.find(" 3 "), 3, " 81.91 ");
  const CarmenLog log = parse(line + "\n");
  const LaserScan& s = log.events[1].laser();
  EXPECT_FALSE(s.valid(0));
  EXPECT_TRUE(s.valid(1));
  EXPECT_DOUBLE_EQ(s.range_max, 80.0);
  CarmenOptions aces;
  aces.no_return_range = 50.0;
  EXPECT_DOUBLE_EQ(parse(line + "\n", aces).events[1].laser().range_max, 50.0);
}

TEST(Carmen, RobotLaser1HasItsOwnGeometryAndMount) {
  // laser 0.2 m ahead and 0.05 m left of the robot, robot at (1, 1) heading π/2
  std::ostringstream s;
  s << "ROBOTLASER1 0 -1.5707963 3.1415927 0.0174533 50.0 0.01 0 181";
  for (int i = 0; i < 181; ++i) s << " 4.0";
  s << " 0 0.95 1.2 1.5707963 1.0 1.0 1.5707963 0.3 0.1 0.55 0.375 1000000.0 1234.5 host 1234.6";
  const CarmenLog log = parse(s.str() + "\n");
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  ASSERT_EQ(log.laserCount(), 1);
  const LaserScan& scan = log.events[1].laser();
  EXPECT_NEAR(scan.angle_min, -1.5707963, 1e-9);
  EXPECT_NEAR(scan.angle_increment, 0.0174533, 1e-9);
  EXPECT_DOUBLE_EQ(scan.range_max, 50.0);
  EXPECT_NEAR(scan.laser_pose.x, 0.2, 1e-6);
  EXPECT_NEAR(scan.laser_pose.y, 0.05, 1e-6);
  EXPECT_NEAR(scan.laser_pose.theta, 0.0, 1e-6);
  EXPECT_EQ(scan.utime, 1234500000);
  // no ODOM lines: the robot pose stands in for odometry
  EXPECT_TRUE(log.odometry_from_robotlaser);
  EXPECT_NEAR(log.events[0].odometry().pose.x, 1.0, 1e-12);
  EXPECT_NEAR(log.events[0].odometry().v, 0.3, 1e-12);
}

TEST(Carmen, RobotLaser1PosesAreDroppedWhenOdomLinesExist) {
  std::ostringstream s;
  s << "ODOM 0.5 0.25 0.1 0.2 0.0 0.0 99.0 host 99.1\n";
  s << "ROBOTLASER1 0 -1.5707963 3.1415927 0.0174533 50.0 0.01 0 181";
  for (int i = 0; i < 181; ++i) s << " 4.0";
  s << " 0 0 0 0 0 0 0 0 0 0 0 0 100.0 host 100.1\n";
  const CarmenLog log = parse(s.str());
  ASSERT_EQ(log.events.size(), 2u);
  EXPECT_FALSE(log.odometry_from_robotlaser);
  EXPECT_EQ(log.events[0].odometry().utime, 99000000);
  EXPECT_NEAR(log.events[0].odometry().pose.theta, 0.1, 1e-12);
  EXPECT_TRUE(log.events[1].isLaser());
  EXPECT_EQ(log.odom_lines, 1);
}

TEST(Carmen, MalformedLinesAreCountedWithLineNumbersAndSkipped) {
  std::ostringstream s;
  s << "# comment\n\n";                                         // 1, 2
  s << flaserLine(181, 2.0, "1.0") << "\n";                      // 3 good
  s << "FLASER 181 1 2 3\n";                                     // 4 too short
  s << "FLASER abc 1 2\n";                                       // 5 bad count
  s << flaserLine(181, 2.0, "1.5").replace(10, 3, " x.y ") << "\n";  // 6 bad range
  s << "ODOM 1 2 3 0 0 0 notatime host 1\n";                     // 7 bad timestamp
  s << "ODOM 1 2 nan 0 0 0 5.0 host 1\n";                        // 8 non-finite pose
  s << "ODOM 1 2 3 0 0 0 5.0 host\n";                            // 9 field count
  s << "FLASER -3\n";                                            // 10 negative count
  s << "PARAM robot_length 0.5 host 1.0\n";                      // 11 skipped kind
  s << "OLD 1 2 3\n";                                            // 12 skipped kind
  s << flaserLine(181, 2.0, "2.0") << "\n";                      // 13 good
  const CarmenLog log = parse(s.str());
  EXPECT_EQ(log.lines, 13);
  EXPECT_EQ(log.comment_lines, 2);
  EXPECT_EQ(log.flaser_lines, 2);
  EXPECT_EQ(log.malformed_count, 7);
  ASSERT_EQ(log.malformed.size(), 7u);
  const std::vector<int64_t> lines{4, 5, 6, 7, 8, 9, 10};
  for (size_t k = 0; k < lines.size(); ++k) EXPECT_EQ(log.malformed[k].line, lines[k]) << log.malformed[k].reason;
  EXPECT_NE(log.malformed[0].reason.find("FLASER"), std::string::npos);
  EXPECT_NE(log.malformed[3].reason.find("timestamp"), std::string::npos);
  EXPECT_EQ(log.skipped_kinds.at("PARAM"), 1);
  EXPECT_EQ(log.skipped_kinds.at("OLD"), 1);
  EXPECT_EQ(log.laserCount(), 2);
  EXPECT_EQ(log.events.back().line, 13);
}

TEST(Carmen, HugeNumbersAreOutOfRangeAndAZeroFieldOfViewIsRefused) {
  std::ostringstream s;
  s << flaserLine(181, 2.0, "1.0").replace(10, 3, " 1e309 ") << "\n";
  s << "ROBOTLASER1 0 -1.5707963 0 0.0174533 50.0 0.01 0 181";
  for (int i = 0; i < 181; ++i) s << " 4.0";
  s << " 0 0 0 0 0 0 0 0 0 0 0 0 100.0 host 100.1\n";
  const CarmenLog log = parse(s.str());
  ASSERT_EQ(log.malformed_count, 2);
  EXPECT_NE(log.malformed[0].reason.find("'1e309' is out of range"), std::string::npos) << log.malformed[0].reason;
  EXPECT_NE(log.malformed[1].reason.find("fov"), std::string::npos) << log.malformed[1].reason;
  EXPECT_EQ(log.laserCount(), 0);
}

TEST(Carmen, OutOfOrderTimestampsAreKeptInFileOrder) {
  const CarmenLog log = parse(flaserLine(181, 2, "5.0") + "\n" + flaserLine(181, 2, "4.0") + "\n" +
                              flaserLine(181, 2, "6.0") + "\n");
  ASSERT_EQ(log.laserCount(), 3);
  std::vector<int64_t> stamps;
  for (const CarmenEvent& e : log.events)
    if (e.isLaser()) stamps.push_back(e.laser().utime);
  EXPECT_EQ(stamps, (std::vector<int64_t>{5000000, 4000000, 6000000}));
  EXPECT_EQ(log.laser_time_reversals, 1);
  // sequence numbers count messages in file order per kind
  EXPECT_EQ(log.events[3].laser().seq, 1);
  EXPECT_EQ(log.events[2].odometry().seq, 1);
}

TEST(Carmen, SecondsToMicrosecondsIsExact) {
  int64_t t = 0;
  ASSERT_TRUE(parseSecondsToUtime("1134864645.90321", t));
  EXPECT_EQ(t, 1134864645903210);
  ASSERT_TRUE(parseSecondsToUtime("12.0000005", t));
  EXPECT_EQ(t, 12000001);
  ASSERT_TRUE(parseSecondsToUtime("-0.5", t));
  EXPECT_EQ(t, -500000);
  ASSERT_TRUE(parseSecondsToUtime("1.5e3", t));
  EXPECT_EQ(t, 1500000000);
  EXPECT_FALSE(parseSecondsToUtime("1.2.3", t));
  EXPECT_FALSE(parseSecondsToUtime("", t));
  EXPECT_FALSE(parseSecondsToUtime(".", t));
  EXPECT_FALSE(parseSecondsToUtime("nan", t));
}

TEST(Carmen, MitCsailLog) {
  const std::string path = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail/mit-csail.clf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const CarmenLog log = readCarmenLogFile(path);
  EXPECT_EQ(log.flaser_lines, 1988);
  EXPECT_EQ(log.malformed_count, 0);
  EXPECT_EQ(log.laserCount(), 1988);
  EXPECT_EQ(log.odometryCount(), 1988);
  const LaserScan& first = log.events[1].laser();
  EXPECT_EQ(first.size(), 361u);
  EXPECT_EQ(first.utime, 1134864629895182);  // first ipc_timestamp, exactly
  int no_return = 0;
  for (size_t i = 0; i < first.size(); ++i)
    if (!first.valid(i)) ++no_return;
  EXPECT_GT(no_return, 10);  // 81.91 readings
}

}  // namespace
}  // namespace polarslam
