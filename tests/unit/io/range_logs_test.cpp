// CMU, Duke and Mines log readers and format detection (data README), on hand-written snippets.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <unistd.h>

#include "io/range_log.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A fresh directory under the system temp dir, removed with the object.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() /
           ("polarslam-range-logs-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

void writeGzip(const std::filesystem::path& path, const std::string& text) {
  gzFile f = gzopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())), static_cast<int>(text.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
}

std::vector<const LaserScan*> scans(const RangeLog& log) {
  std::vector<const LaserScan*> out;
  for (const RangeLogEvent& e : log.events)
    if (e.isLaser()) out.push_back(&e.laser());
  return out;
}
std::vector<const OdometryReading*> odometries(const RangeLog& log) {
  std::vector<const OdometryReading*> out;
  for (const RangeLogEvent& e : log.events)
    if (!e.isLaser()) out.push_back(&e.odometry());
  return out;
}

// ---------------------------------------------------------------------------------------- CMU

/// L line: robot at (x, y, theta) cm/rad, laser 25 cm ahead, ranges 100 + i cm (i = beam index).
std::string cmuLaserLine(double x, double y, double theta, const std::string& ts, int beams = 180) {
  std::ostringstream s;
  s << "L " << x << " " << y << " " << theta << " " << x + 25.0 * std::cos(theta) << " "
    << y + 25.0 * std::sin(theta) << " " << theta;
  for (int i = 0; i < beams; ++i) s << " " << (i == 7 ? 8183 : 100 + i);
  s << " " << ts;
  return s.str();
}

RangeLog parseCmu(const std::string& text, const CmuOptions& options = {}) {
  std::istringstream in(text);
  return readCmuLog(in, options);
}

TEST(CmuLog, OdometryInMetresAndExactTimes) {
  const RangeLog log = parseCmu("O 100 -50 0.5 1.25\nO 250.5 0 -0.25 0.079745\n");
  EXPECT_EQ(log.format, "cmu");
  ASSERT_EQ(log.events.size(), 2u);
  const OdometryReading& o = log.events[0].odometry();
  EXPECT_DOUBLE_EQ(o.pose.x, 1.0);
  EXPECT_DOUBLE_EQ(o.pose.y, -0.5);
  EXPECT_DOUBLE_EQ(o.pose.theta, 0.5);
  EXPECT_EQ(o.utime, 1250000);
  EXPECT_EQ(log.events[1].odometry().utime, 79745);
  EXPECT_DOUBLE_EQ(log.events[1].odometry().pose.x, 2.505);
  EXPECT_EQ(log.events[1].odometry().seq, 1);
  EXPECT_EQ(log.line_kinds.at("O"), 2);
}

TEST(CmuLog, LaserLineGivesOdometryThenScan) {
  const RangeLog log = parseCmu(cmuLaserLine(-94.234, -139.954, -1.342158, "0.025466") + "\n");
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  ASSERT_EQ(log.events.size(), 2u);
  ASSERT_FALSE(log.events[0].isLaser());
  ASSERT_TRUE(log.events[1].isLaser());
  const OdometryReading& o = log.events[0].odometry();
  EXPECT_NEAR(o.pose.x, -0.94234, 1e-12);
  EXPECT_NEAR(o.pose.y, -1.39954, 1e-12);
  EXPECT_EQ(o.utime, 25466);
  const LaserScan& s = log.events[1].laser();
  EXPECT_EQ(s.utime, 25466);
  ASSERT_EQ(s.size(), 180u);
  EXPECT_FLOAT_EQ(s.ranges[0], 1.0f);     // cm -> m
  EXPECT_FLOAT_EQ(s.ranges[179], 2.79f);
  // from the right, counter-clockwise, 1° steps: the CARMEN 180-beam grid −90°..+89°
  EXPECT_NEAR(s.bearing(0), -90.0 * kDeg, 1e-12);
  EXPECT_NEAR(s.bearing(90), 0.0, 1e-12);
  EXPECT_NEAR(s.bearing(179), 89.0 * kDeg, 1e-12);
  // 8183 cm = no return, beyond range_max
  EXPECT_FALSE(s.valid(7));
  EXPECT_TRUE(s.valid(6));
  EXPECT_DOUBLE_EQ(s.range_max, 80.0);
  EXPECT_DOUBLE_EQ(s.laser_pose.x, 0.25);
  EXPECT_DOUBLE_EQ(s.laser_pose.y, 0.0);
  EXPECT_EQ(log.events[1].line, 1);
}

TEST(CmuLog, LaserLinePosesCanBeLeftOut) {
  CmuOptions options;
  options.odometry_from_laser_lines = false;
  options.laser_pose = Pose2{0.1, 0.0, 0.0};
  const RangeLog log = parseCmu("O 0 0 0 0.1\n" + cmuLaserLine(0, 0, 0, "0.2") + "\n", options);
  ASSERT_EQ(log.events.size(), 2u);
  EXPECT_FALSE(log.events[0].isLaser());
  EXPECT_TRUE(log.events[1].isLaser());
  EXPECT_DOUBLE_EQ(log.events[1].laser().laser_pose.x, 0.1);
}

TEST(CmuLog, MalformedLinesAreCountedWithLineNumbers) {
  std::ostringstream s;
  s << "# comment\n";                                     // 1
  s << "O 1 2 0.1 0.5\n";                                 // 2 good
  s << cmuLaserLine(0, 0, 0, "0.6", 179) << "\n";         // 3 one beam short
  s << "O 1 2 0.1 later\n";                               // 4 bad time
  s << "O 1 2 0.1 0.5 9\n";                               // 5 extra field
  s << "O 1 nan 0.1 0.7\n";                               // 6 non-finite
  s << "X 1 2 3\n";                                       // 7 unknown kind, skipped
  s << cmuLaserLine(0, 0, 0, "0.8") << "\n";              // 8 good
  const RangeLog log = parseCmu(s.str());
  EXPECT_EQ(log.lines, 8);
  EXPECT_EQ(log.comment_lines, 1);
  EXPECT_EQ(log.malformed_count, 4);
  ASSERT_EQ(log.malformed.size(), 4u);
  const std::vector<int64_t> lines{3, 4, 5, 6};
  for (size_t k = 0; k < lines.size(); ++k) EXPECT_EQ(log.malformed[k].line, lines[k]) << log.malformed[k].reason;
  EXPECT_NE(log.malformed[0].reason.find("L: expected"), std::string::npos) << log.malformed[0].reason;
  EXPECT_NE(log.malformed[1].reason.find("ts"), std::string::npos) << log.malformed[1].reason;
  EXPECT_EQ(log.skipped_kinds.at("X"), 1);
  EXPECT_EQ(log.laserCount(), 1);
  EXPECT_EQ(log.odometryCount(), 2);
}

TEST(CmuLog, ReadsGzipAndPlainFilesAlike) {
  TempDir dir;
  const std::string text = "O 100 0 0 0.5\n" + cmuLaserLine(100, 0, 0, "0.6") + "\n";
  writeGzip(dir.path / "robotdata.log.gz", text);
  {
    std::ofstream plain(dir.path / "robotdata.log");
    plain << text;
  }
  for (const char* name : {"robotdata.log.gz", "robotdata.log"}) {
    const RangeLog log = readCmuLogFile((dir.path / name).string());
    ASSERT_EQ(log.events.size(), 3u) << name;
    EXPECT_DOUBLE_EQ(log.events[0].odometry().pose.x, 1.0) << name;
    EXPECT_EQ(log.events[2].laser().utime, 600000) << name;
  }
  EXPECT_THROW(readCmuLogFile((dir.path / "absent.log").string()), std::runtime_error);
}

TEST(CmuLog, TruncatedGzipIsAnErrorNotAShortLog) {
  TempDir dir;
  std::string text;
  for (int k = 0; k < 200; ++k) text += cmuLaserLine(k, 0, 0, std::to_string(k) + ".5") + "\n";
  const auto path = dir.path / "robotdata.log.gz";
  writeGzip(path, text);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  try {
    readCmuLogFile(path.string());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

TEST(CmuLog, CarmenFilesMayBeGzipToo) {
  TempDir dir;
  std::ostringstream flaser;
  flaser << "FLASER 181";
  for (int i = 0; i < 181; ++i) flaser << " 2.5";
  flaser << " 0 0 0 1 2 0.25 1134864645.903210 host 12.5\n";
  writeGzip(dir.path / "log.clf.gz", flaser.str());
  const RangeLog log = readRangeLogFile((dir.path / "log.clf.gz").string());
  EXPECT_EQ(log.format, "carmen");
  ASSERT_EQ(log.laserCount(), 1);
  EXPECT_EQ(scans(log)[0]->utime, 1134864645903210);
  EXPECT_EQ(readCarmenLogFile((dir.path / "log.clf.gz").string()).flaser_lines, 1);
}

// ---------------------------------------------------------------------------------------- Duke

std::string dukeLaserLine(int beams, double range) {
  std::ostringstream s;
  s << "Laser " << beams;
  for (int i = 0; i < beams; ++i) s << " " << (i == 3 ? 8.183001 : range);
  return s.str();
}

RangeLog parseDuke(const std::string& text, const DukeOptions& options = {}) {
  std::istringstream in(text);
  return readDukeLog(in, options);
}

TEST(DukeLog, PairsGetNominalTimes) {
  const std::string pair = "Odometry -2.424026 4.800517 2.590948 \n" + dukeLaserLine(181, 1.5) + "\n";
  const RangeLog log = parseDuke(pair + "Odometry 0.5 0.25 3.5\n" + dukeLaserLine(181, 2.0) + "\n");
  EXPECT_EQ(log.format, "duke");
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  ASSERT_EQ(log.events.size(), 4u);
  const auto odo = odometries(log);
  const auto scan = scans(log);
  ASSERT_EQ(odo.size(), 2u);
  ASSERT_EQ(scan.size(), 2u);
  EXPECT_DOUBLE_EQ(odo[0]->pose.x, -2.424026);  // metres, absolute pose
  EXPECT_DOUBLE_EQ(odo[0]->pose.theta, 2.590948);
  EXPECT_NEAR(odo[1]->pose.theta, 3.5 - 2.0 * std::numbers::pi, 1e-12);  // wrapped
  EXPECT_EQ(odo[0]->utime, 0);
  EXPECT_EQ(scan[0]->utime, 0);
  EXPECT_EQ(odo[1]->utime, 200000);
  EXPECT_EQ(scan[1]->utime, 200000);
  EXPECT_FALSE(log.events[0].isLaser());  // odometry first, as in the file
  // 181 beams: 1° over −90°..+90°
  EXPECT_NEAR(scan[0]->bearing(0), -90.0 * kDeg, 1e-12);
  EXPECT_NEAR(scan[0]->bearing(180), 90.0 * kDeg, 1e-9);
  EXPECT_FLOAT_EQ(scan[0]->ranges[0], 1.5f);
  EXPECT_FALSE(scan[0]->valid(3));  // 8.183 = no return
  EXPECT_TRUE(scan[0]->valid(4));
  EXPECT_DOUBLE_EQ(scan[0]->range_max, 8.18);
  EXPECT_DOUBLE_EQ(scan[0]->laser_pose.x, 0.0);
  EXPECT_EQ(log.line_kinds.at("Laser"), 2);
  ASSERT_EQ(log.notes.size(), 1u);
  EXPECT_NE(log.notes[0].find("0.2 s"), std::string::npos) << log.notes[0];
}

TEST(DukeLog, PeriodOptionAndMalformedLinesKeepTheirSlot) {
  DukeOptions options;
  options.period = 0.1;
  std::ostringstream s;
  s << "Odometry 0 0 0\n" << dukeLaserLine(181, 1.0) << "\n";  // 1, 2: slot 0
  s << "Odometry 0.1 0 0\n" << dukeLaserLine(181, 1.0).substr(0, 30) << "\n";  // 3 slot 1, 4 cut short
  s << "Odometry 0.2 zero 0\n" << dukeLaserLine(181, 1.0) << "\n";  // 5 bad y (slot 2), 6 slot 2
  s << dukeLaserLine(3, 1.0) << "\n";  // 7: a laser with no odometry opens slot 3; odd beam count
  const RangeLog log = parseDuke(s.str(), options);
  EXPECT_EQ(log.malformed_count, 2);
  ASSERT_EQ(log.malformed.size(), 2u);
  EXPECT_EQ(log.malformed[0].line, 4);
  EXPECT_EQ(log.malformed[1].line, 5);
  EXPECT_NE(log.malformed[1].reason.find("Odometry: y"), std::string::npos) << log.malformed[1].reason;
  const auto scan = scans(log);
  ASSERT_EQ(scan.size(), 3u);
  EXPECT_EQ(scan[0]->utime, 0);
  EXPECT_EQ(scan[1]->utime, 200000);
  EXPECT_EQ(scan[2]->utime, 300000);
  EXPECT_EQ(log.unusual_beam_counts, 1);
  const auto odo = odometries(log);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_EQ(odo[1]->utime, 100000);
}

// ---------------------------------------------------------------------------------------- Mines

/// A 707-column Mines line; range i is `range_mm(i)`.
template <typename Range>
std::string minesLine(int64_t utime, int64_t left, int64_t right, Range range_mm) {
  std::ostringstream s;
  s << utime << " 14554 " << left << " " << right;
  for (int c = 4; c < 24; ++c) s << (c == 7 ? " 167.2" : " 0");  // as in exp2.dat
  for (int i = 0; i < 682; ++i) s << " " << range_mm(i);
  s << " 0";
  return s.str();
}
std::string minesLine(int64_t utime, int64_t left, int64_t right) {
  return minesLine(utime, left, right, [](int i) { return i == 5 ? 0 : i == 6 ? 7 : 1500 + i; });
}

RangeLog parseMines(const std::string& text, const MinesOptions& options = {}) {
  std::istringstream in(text);
  return readMinesLog(in, options);
}

TEST(MinesLog, ScansInMetresOverTheUrgField) {
  const RangeLog log = parseMines(minesLine(361431443, 234835, 231727) + "\n");
  EXPECT_EQ(log.format, "mines");
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  ASSERT_EQ(log.events.size(), 2u);
  EXPECT_FALSE(log.events[0].isLaser());
  const LaserScan& s = log.events[1].laser();
  EXPECT_EQ(s.utime, 361431443);  // µs, as logged
  EXPECT_EQ(log.events[0].odometry().utime, 361431443);
  ASSERT_EQ(s.size(), 682u);
  EXPECT_FLOAT_EQ(s.ranges[0], 1.5f);  // column 24, mm -> m
  EXPECT_FLOAT_EQ(s.ranges[681], 2.181f);  // column 705
  EXPECT_TRUE(std::isinf(s.ranges[5]));  // 0 = no return
  EXPECT_TRUE(std::isinf(s.ranges[6]));  // URG error code
  EXPECT_FALSE(s.valid(5));
  EXPECT_FALSE(s.valid(6));
  EXPECT_TRUE(s.valid(7));
  // 360°/1024 steps, counter-clockwise, centred on the heading
  const double step = 360.0 / 1024.0 * kDeg;
  EXPECT_NEAR(s.angle_increment, step, 1e-15);
  EXPECT_NEAR(s.bearing(0), -340.5 * step, 1e-12);
  EXPECT_NEAR(s.bearing(681), 340.5 * step, 1e-12);
  EXPECT_NEAR(s.bearing(340) + s.bearing(341), 0.0, 1e-12);
  EXPECT_NEAR(s.bearing(681) - s.bearing(0), 239.4 * kDeg, 0.1 * kDeg);
  EXPECT_DOUBLE_EQ(s.laser_pose.x, 0.07);
  // the first line sets the odometry origin
  EXPECT_DOUBLE_EQ(log.events[0].odometry().pose.x, 0.0);
  EXPECT_DOUBLE_EQ(log.events[0].odometry().pose.theta, 0.0);
}

TEST(MinesLog, WheelCountsIntegrateAsDifferentialDrive) {
  std::ostringstream s;
  s << minesLine(1000, 5000, 7000) << "\n";
  s << minesLine(2000, 7000, 9000) << "\n";  // both wheels one turn (2000 counts) forward
  s << minesLine(3000, 6000, 10000) << "\n";  // left back half a turn, right forward half a turn
  const RangeLog log = parseMines(s.str());
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  const auto odo = odometries(log);
  ASSERT_EQ(odo.size(), 3u);
  const double turn = 2.0 * std::numbers::pi * 0.077;  // one wheel circumference
  EXPECT_NEAR(odo[1]->pose.x, turn, 1e-12);
  EXPECT_NEAR(odo[1]->pose.y, 0.0, 1e-12);
  EXPECT_NEAR(odo[1]->pose.theta, 0.0, 1e-12);
  // on the spot: dθ = (dr − dl) / (2·half_axle) = turn / 0.33, counter-clockwise (right wheel forward)
  EXPECT_NEAR(odo[2]->pose.x, turn, 1e-12);
  EXPECT_NEAR(odo[2]->pose.theta, turn / 0.33, 1e-12);
  EXPECT_EQ(odo[2]->utime, 3000);
}

TEST(MinesLog, CounterWrapGivesTheSmallStep) {
  std::ostringstream s;
  s << minesLine(1000, 4294966296, 2147483000) << "\n";  // 2^32 − 1000; 2^31 − 648
  s << minesLine(2000, 1000, -2147482296) << "\n";       // +2000 through 2^32; +2000 through 2^31
  const RangeLog log = parseMines(s.str());
  ASSERT_EQ(log.malformed_count, 0) << log.malformed[0].reason;
  const auto odo = odometries(log);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_NEAR(odo[1]->pose.x, 2.0 * std::numbers::pi * 0.077, 1e-12);
  EXPECT_NEAR(odo[1]->pose.theta, 0.0, 1e-12);
}

TEST(MinesLog, MalformedLinesAreCountedAndOdometryContinues) {
  std::ostringstream s;
  s << minesLine(1000, 0, 0) << "\n";                                // 1
  s << "1 2 3 4 5\n";                                                // 2 column count
  std::string bad = minesLine(1500, 100, 100);
  bad.replace(bad.find(" 100 100 "), 9, " 100 1e2 ");
  s << bad << "\n";                                                  // 3 tick not an integer
  s << minesLine(2000, 1000, 1000, [](int i) { return i == 9 ? std::string("x") : std::string("1000"); }) << "\n";  // 4
  s << minesLine(3000, 2000, 2000) << "\n";                          // 5
  const RangeLog log = parseMines(s.str());
  EXPECT_EQ(log.malformed_count, 3);
  ASSERT_EQ(log.malformed.size(), 3u);
  EXPECT_EQ(log.malformed[0].line, 2);
  EXPECT_NE(log.malformed[0].reason.find("columns"), std::string::npos) << log.malformed[0].reason;
  EXPECT_EQ(log.malformed[1].line, 3);
  EXPECT_NE(log.malformed[1].reason.find("right wheel"), std::string::npos) << log.malformed[1].reason;
  EXPECT_EQ(log.malformed[2].line, 4);
  EXPECT_NE(log.malformed[2].reason.find("range 9"), std::string::npos) << log.malformed[2].reason;
  const auto odo = odometries(log);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_NEAR(odo[1]->pose.x, 2.0 * std::numbers::pi * 0.077, 1e-12);  // 0 -> 2000 counts
  EXPECT_EQ(log.events.back().line, 5);
}

// ---------------------------------------------------------------------------------------- detection

TEST(RangeLogFormat, DetectedFromTheFirstDataLine) {
  EXPECT_EQ(detectRangeLogFormat("# x\n\nPARAM robot_length 0.5 host 1\nFLASER 1 1 0 0 0 0 0 0 1 h 1\n", "a.txt"),
            RangeLogFormat::Carmen);
  EXPECT_EQ(detectRangeLogFormat("O 1 2 3 0.1\n", "r.log"), RangeLogFormat::Cmu);
  EXPECT_EQ(detectRangeLogFormat(cmuLaserLine(0, 0, 0, "0.1") + "\n", "r.log"), RangeLogFormat::Cmu);
  EXPECT_EQ(detectRangeLogFormat("Odometry 1 2 3\n", "loop.log"), RangeLogFormat::Duke);
  EXPECT_EQ(detectRangeLogFormat(minesLine(1, 2, 3) + "\n", "x.txt"), RangeLogFormat::Mines);
  // no data lines: the extension decides
  EXPECT_EQ(detectRangeLogFormat("# empty\n", "a.clf"), RangeLogFormat::Carmen);
  EXPECT_EQ(detectRangeLogFormat("", "exp.DAT.gz"), RangeLogFormat::Mines);
  EXPECT_THROW(detectRangeLogFormat("", "a.txt"), TextFormatError);
}

TEST(RangeLogFormat, NotALogNamesFileAndLine) {
  try {
    detectRangeLogFormat("# notes\nhello world\n", "notes.txt");
    FAIL() << "no error";
  } catch (const TextFormatError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("notes.txt:2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'hello'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(detectRangeLogFormat("1 2 3\n", "short.dat"), TextFormatError);  // integers, too few columns
  try {
    detectRangeLogFormat(std::string("LCM\0\x01\x02", 6), "run.lcmlog");
    FAIL() << "no error";
  } catch (const TextFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("binary"), std::string::npos) << e.what();
  }
}

TEST(RangeLogFormat, NamesRoundTrip) {
  for (RangeLogFormat f : {RangeLogFormat::Auto, RangeLogFormat::Carmen, RangeLogFormat::Cmu, RangeLogFormat::Duke,
                           RangeLogFormat::Mines})
    EXPECT_EQ(parseRangeLogFormat(rangeLogFormatName(f)), f);
  EXPECT_FALSE(parseRangeLogFormat("clf").has_value());
}

TEST(RangeLogFormat, ReadFileDetectsAndAppliesOptions) {
  TempDir dir;
  writeGzip(dir.path / "robotdata.log.gz", "O 100 0 0 0.5\n" + cmuLaserLine(100, 0, 0, "0.6") + "\n");
  RangeLogOptions options;
  options.cmu.laser_pose = Pose2{0.3, 0.0, 0.0};
  const RangeLog log = readRangeLogFile((dir.path / "robotdata.log.gz").string(), RangeLogFormat::Auto, options);
  EXPECT_EQ(log.format, "cmu");
  ASSERT_EQ(log.laserCount(), 1);
  EXPECT_DOUBLE_EQ(scans(log)[0]->laser_pose.x, 0.3);
  // a forced format reads the lines as that format: here every line is another kind
  const RangeLog as_duke = readRangeLogFile((dir.path / "robotdata.log.gz").string(), RangeLogFormat::Duke);
  EXPECT_TRUE(as_duke.events.empty());
  EXPECT_EQ(as_duke.skipped_kinds.at("O"), 1);
  EXPECT_THROW(readRangeLogFile((dir.path / "absent.clf").string()), std::runtime_error);
}

// ---------------------------------------------------------------------------------------- shared data

std::string sharedData(const std::string& relative) { return std::string(POLARSLAM_SHARED_DATA_DIR) + "/" + relative; }

TEST(RangeLogSharedData, CmuWeanHall) {
  const std::string path = sharedData("cmu-wean-hall/robotdata1.log.gz");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const RangeLog log = readRangeLogFile(path);
  EXPECT_EQ(log.format, "cmu");
  EXPECT_EQ(log.malformed_count, 0);
  EXPECT_EQ(log.line_kinds.at("L"), 713);
  EXPECT_EQ(log.line_kinds.at("O"), 1505);
  EXPECT_EQ(log.laserCount(), 713);
  EXPECT_EQ(log.laser_time_reversals, 0);
}

TEST(RangeLogSharedData, DukeLoop5) {
  const std::string path = sharedData("duke-loop5/loop5.log");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const RangeLog log = readRangeLogFile(path);
  EXPECT_EQ(log.format, "duke");
  EXPECT_EQ(log.malformed_count, 0);
  EXPECT_EQ(log.laserCount(), 551);
  EXPECT_EQ(log.odometryCount(), 551);
  EXPECT_EQ(scans(log).back()->utime, 550 * 200000);
}

TEST(RangeLogSharedData, MinesExp2) {
  const std::string path = sharedData("mines-paristech/exp2.dat");
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data absent: " << path;
  const RangeLog log = readRangeLogFile(path);
  EXPECT_EQ(log.format, "mines");
  EXPECT_EQ(log.malformed_count, 0);
  EXPECT_EQ(log.laserCount(), 641);
  EXPECT_EQ(scans(log).front()->utime, 361431443);
}

}  // namespace
}  // namespace polarslam
