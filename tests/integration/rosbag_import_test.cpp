// ROS 1 bags in: a bag written with the rosbag library (sensor_msgs/LaserScan, nav_msgs/Odometry,
// a static tf for the laser mount) and the same data as a CARMEN log import to the same LCM log
// content, and PSM SLAM over each gives the same trajectory.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>

#include "child_process.hpp"
#include "io/range_log.hpp"
#include "io/tum.hpp"
#include "unit/slam/synthetic_run.hpp"
#ifdef POLARSLAM_HAVE_ROSBAG
#include "rosbag/ros_bag_log.hpp"
#include "rosbag/ros_bag_records.hpp"
#endif

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::readFile;
using polarslam::testing::runToEnd;

namespace polarslam {
namespace {

constexpr double kNoReturn = 81.91;  // what CARMEN logs write for a beam without return

std::string carmenSeconds(int64_t utime) {
  char text[40];
  std::snprintf(text, sizeof text, "%lld.%06lld", static_cast<long long>(utime / 1'000'000),
                static_cast<long long>(utime % 1'000'000));
  return text;
}

/// The run as a CARMEN log: one FLASER line per scan, its odometry in the pose fields.
void writeCarmen(const std::string& path, const ::polarslam::testing::SyntheticRun& run) {
  std::ofstream out(path);
  for (size_t k = 0; k < run.scans.size(); ++k) {
    const LaserScan& s = run.scans[k];
    const Pose2& o = run.odometry[k].pose;
    out << "FLASER " << s.ranges.size();
    char value[32];
    for (float r : s.ranges) {
      std::snprintf(value, sizeof value, " %.9g", std::isfinite(r) ? static_cast<double>(r) : kNoReturn);
      out << value;
    }
    out << std::setprecision(17);
    for (int twice = 0; twice < 2; ++twice) out << ' ' << o.x << ' ' << o.y << ' ' << o.theta;  // laser pose, odometry
    out << ' ' << carmenSeconds(s.utime) << " host " << carmenSeconds(s.utime) << "\n";
  }
}

#ifdef POLARSLAM_HAVE_ROSBAG
/// The same run as a bag: scan and odometry at each scan time, the laser at the robot's origin
/// through a two-step static tf chain.
void writeBag(const std::string& path, const ::polarslam::testing::SyntheticRun& run) {
  namespace records = rosbag_records;
  records::BagWriter bag(path);
  const int64_t t0 = run.scans.front().utime;
  bag.writeStatic({"base_link", "laser_mount", 0.3, 0.1, 0.5}, t0);
  bag.writeStatic({"laser_mount", "laser", -0.3 * std::cos(0.5) - 0.1 * std::sin(0.5),
                   0.3 * std::sin(0.5) - 0.1 * std::cos(0.5), -0.5},
                  t0);  // undoes the first step: the laser sits at the origin
  for (size_t k = 0; k < run.scans.size(); ++k) {
    const LaserScan& s = run.scans[k];
    records::Scan scan{"/scan", "laser", s.utime, static_cast<uint32_t>(k), s.angle_min, s.angle_increment, 0.0,
                       0.0,     kNoReturn - 1.0, {}};
    for (float r : s.ranges) scan.ranges.push_back(std::isfinite(r) ? r : std::numeric_limits<float>::infinity());
    records::Odometry odometry;
    odometry.topic = "/odom";
    odometry.child_frame = "base_link";
    odometry.utime = s.utime;
    odometry.seq = static_cast<uint32_t>(k);
    odometry.x = run.odometry[k].pose.x;
    odometry.y = run.odometry[k].pose.y;
    odometry.yaw = run.odometry[k].pose.theta;
    bag.write(scan);  // the scan first: the importer still puts odometry first at equal times
    bag.write(odometry);
  }
}
#endif

std::vector<PoseStamped> trajectoryOf(const std::filesystem::path& dir, const std::string& log,
                                      const std::string& name) {
  EXPECT_EQ(runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", "psm-slam", "--out", (dir / name).string()},
                     dir / (name + ".out"), 120s),
            0)
      << readFile(dir / (name + ".out"));
  return readTumTrajectory((dir / name / "trajectory.tum").string());
}

TEST(RosBagImport, ABagImportsAsTheSameDataFromCarmenAndPsmSlamAgrees) {
#ifndef POLARSLAM_HAVE_ROSBAG
  GTEST_SKIP() << "built without ROS 1 bag support (librosbag-dev missing)";
#else
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-rosbag-it-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto run = ::polarslam::testing::simulateLoopRun(::polarslam::testing::makeLoopWorld(), {});
  const std::string bag = (dir / "run.bag").string(), clf = (dir / "run.clf").string();
  writeBag(bag, run);
  writeCarmen(clf, run);

  const RangeLog from_bag = readRosBag(bag);
  const RangeLog from_carmen = readRangeLogFile(clf);
  ASSERT_EQ(from_bag.events.size(), from_carmen.events.size());
  for (size_t i = 0; i < from_bag.events.size(); ++i) {
    const RangeLogEvent &a = from_bag.events[i], &b = from_carmen.events[i];
    ASSERT_EQ(a.isLaser(), b.isLaser()) << i;
    ASSERT_EQ(a.utime(), b.utime()) << i;
    if (!a.isLaser()) {
      EXPECT_NEAR(a.odometry().pose.x, b.odometry().pose.x, 1e-12);
      EXPECT_NEAR(a.odometry().pose.theta, b.odometry().pose.theta, 1e-12);
      continue;
    }
    ASSERT_EQ(a.laser().ranges.size(), b.laser().ranges.size());
    for (size_t r = 0; r < a.laser().ranges.size(); ++r)
      ASSERT_TRUE(a.laser().ranges[r] == b.laser().ranges[r] || !b.laser().valid(r)) << i << " beam " << r;
    EXPECT_NEAR(a.laser().laser_pose.x, 0.0, 1e-12) << "the tf chain places the laser at the origin";
    EXPECT_NEAR(a.laser().laser_pose.theta, 0.0, 1e-12);
    EXPECT_NEAR(a.laser().angle_min, b.laser().angle_min, 1e-7) << "float32 in the bag";
  }

  for (const std::string& input : {bag, clf}) {
    const std::string lcm = input + ".lcmlog";
    ASSERT_EQ(runToEnd({binPath("polarslam"), "import", input, "-o", lcm}, dir / "import.out", 60s), 0)
        << readFile(dir / "import.out");
  }
  const auto with_bag = trajectoryOf(dir, bag + ".lcmlog", "bag"), with_carmen = trajectoryOf(dir, clf + ".lcmlog", "clf");
  ASSERT_EQ(with_bag.size(), run.scans.size());
  ASSERT_EQ(with_bag.size(), with_carmen.size());
  double worst = 0.0;
  for (size_t i = 0; i < with_bag.size(); ++i)
    worst = std::max(worst, (with_bag[i].pose.translation() - with_carmen[i].pose.translation()).norm());
  EXPECT_LT(worst, 1e-3) << "PSM SLAM over the bag and over the CARMEN log";
  if (!HasFailure()) std::filesystem::remove_all(dir);
#endif
}

}  // namespace
}  // namespace polarslam
