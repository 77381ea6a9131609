// polarslam-grid and path following over real LCM.
//  1. Scans with exact anchors but wrong scan-time poses (a map that has since moved) go in on
//     LASER / SCAN_ANCHORS / SLAM_MAP; on GRID_REQUEST the process regenerates the true poses
//     (GRID_PATH), writes map.{bt,ot,pgm,yaml,png} (GRID_STATUS), and on GOAL publishes a
//     collision-free PLANNED_PATH; a malformed message is rejected and counted.
//  2. polarslam-sim --path-channel follows a PLANNED_PATH to its goal and stops there.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "child_process.hpp"
#include "common/lcm_convert.hpp"
#include "common/path_messages.hpp"
#include "common/pose_graph_message.hpp"
#include "common/process_context.hpp"
#include "grid/anchor_model.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_map_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"
#include "polarslam/process_status_t.hpp"
#include "sim/world.hpp"
#include "unit/grid/grid_fixtures.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::sourcePath;

namespace polarslam {
namespace {

struct Listener {
  std::optional<polarslam::grid_status_t> written;
  std::optional<polarslam::path_t> grid_path, planned_path;
  std::optional<Pose2> truth;
  int64_t grid_rejected = -1;

  template <typename Msg>
  static bool decode(const lcm::ReceiveBuffer* rbuf, Msg& msg) {
    return msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0;
  }
  void onStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::grid_status_t msg;
    if (decode(rbuf, msg) && msg.state == "written") written = msg;
  }
  void onGridPath(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::path_t msg;
    if (decode(rbuf, msg)) grid_path = msg;
  }
  void onPlannedPath(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::path_t msg;
    if (decode(rbuf, msg)) planned_path = msg;
  }
  void onProcessStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::process_status_t msg;
    if (decode(rbuf, msg) && msg.name == "polarslam-grid") grid_rejected = msg.messages_rejected;
  }
  void onTruth(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::pose_t msg;
    PoseStamped pose;
    if (decode(rbuf, msg) && fromLcm(msg, pose).empty()) truth = pose.pose;
  }
};

/// Handles messages until `done()` or the timeout; returns done().
template <typename Done>
bool handleUntil(lcm::LCM& lcm, std::chrono::milliseconds timeout, Done done) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done() && std::chrono::steady_clock::now() < end) lcm.handleTimeout(20);
  return done();
}

/// Infinite lines through the world's straight walls, as an EKF would map them.
FeatureMap wallLines(const World& world) {
  FeatureMap map;
  for (const WallSegment& s : world.segments()) {
    const Vec2 n = s.normal();
    double alpha = std::atan2(n.y(), n.x()), d = n.dot(s.a);
    if (d < 0) {
      d = -d;
      alpha = wrapAngle(alpha + std::numbers::pi);
    }
    MapFeature f;
    f.id = static_cast<int64_t>(map.features.size()) + 1;
    f.kind = MapFeatureKind::Line;
    f.params = {alpha, d, 0.0};
    f.cov.topLeftCorner<2, 2>() = Mat2::Identity() * 1e-6;
    f.endpoint_a = s.a;
    f.endpoint_b = s.b;
    map.features.push_back(f);
  }
  return map;
}

ScanAnchors exactAnchors(int64_t utime, const Pose2& truth, const Pose2& stored, const FeatureMap& map) {
  ScanAnchors a;
  a.utime = utime;
  a.pose.utime = utime;
  a.pose.pose = stored;
  a.pose.cov = Mat3::Identity() * 1e-4;
  for (const MapFeature& f : map.features) {
    const AnchorPrediction p = predictAnchor(truth, f);
    if (!p.valid || p.z.y() > 7.0) continue;
    a.anchors.push_back({f.id, f.kind, p.z, Vec3(1e-5, 1e-5, 0).asDiagonal()});
  }
  return a;
}

TEST(GridProcess, RegeneratesWritesTheGridAndPlansToAGoal) {
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-it-grid-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  Listener listener;
  lcm.subscribe("GRID_STATUS", &Listener::onStatus, &listener);
  lcm.subscribe("GRID_PATH", &Listener::onGridPath, &listener);
  lcm.subscribe("PLANNED_PATH", &Listener::onPlannedPath, &listener);
  lcm.subscribe("PROCESS_STATUS", &Listener::onProcessStatus, &listener);
  ChildProcess grid({binPath("polarslam-grid"), "--out", (dir / "maps").string(), "--period", "0", "--min-translation",
                     "0"},
                    (dir / "grid.log").string());
  std::this_thread::sleep_for(700ms);  // let it join the group

  const World world = test::twoRoomWorld();
  const FeatureMap map = wallLines(world);
  lcm.publish("SLAM_MAP", &static_cast<const polarslam::slam_map_t&>(toLcm(map, 0)));
  const std::vector<Pose2> poses = test::twoRoomPoses();
  const Pose2 map_moved(0.06, -0.04, 0.015);  // scan-time poses are off: the map moved since
  for (size_t k = 0; k < poses.size(); ++k) {
    const int64_t utime = 1'000'000 * static_cast<int64_t>(k + 1);
    polarslam::laser_scan_t scan = toLcm(test::castScan(world, poses[k], 361, 2 * std::numbers::pi, utime));
    scan.seq = static_cast<int64_t>(k);
    lcm.publish("LASER", &scan);
    lcm.publish("SCAN_ANCHORS",
                &static_cast<const polarslam::scan_anchors_t&>(
                    toLcm(exactAnchors(utime, poses[k], map_moved * poses[k], map), static_cast<int64_t>(k))));
    std::this_thread::sleep_for(20ms);
  }
  const std::vector<uint8_t> garbage = {9, 9, 9};
  lcm.publish("SCAN_ANCHORS", garbage.data(), static_cast<unsigned>(garbage.size()));
  lcm.publish("SLAM_POSE", &static_cast<const polarslam::pose_t&>(toLcm(PoseStamped{7'000'000, {1.0, 0.8, 0.0}, Mat3::Identity() * 1e-4}, "map")));
  // Folders from the network must stay below --out: these two are refused and counted.
  for (const std::string outside : {"/tmp/polarslam-grid-request-escape", "../escape"}) {
    polarslam::grid_request_t bad{};
    bad.utime = 6'000'000;
    bad.out_dir = outside;
    lcm.publish("GRID_REQUEST", &bad);
  }
  polarslam::grid_request_t request{};
  request.utime = 7'000'000;
  lcm.publish("GRID_REQUEST", &request);

  ASSERT_TRUE(handleUntil(lcm, 30s, [&] { return listener.written && listener.grid_path; }))
      << "no grid written; see " << (dir / "grid.log");
  EXPECT_EQ(listener.written->scans_stored, static_cast<int32_t>(poses.size()));
  EXPECT_EQ(listener.written->regenerated, static_cast<int32_t>(poses.size()));
  EXPECT_GT(listener.written->occupied_cells, 300);
  EXPECT_NEAR(listener.written->mean_shift_m, Vec2(0.06, 0.04).norm(), 0.05);
  const polarslam::path_t& path = *listener.grid_path;
  ASSERT_EQ(path.num_poses, static_cast<int32_t>(poses.size()));
  for (size_t k = 0; k < poses.size(); ++k) {
    EXPECT_EQ(path.source[k], polarslam::path_t::REGENERATED);
    EXPECT_NEAR(path.x[k], poses[k].x, 1e-4);
    EXPECT_NEAR(path.y[k], poses[k].y, 1e-4);
  }
  const auto maps = dir / "maps";
  octomap::OcTree bt(0.1);
  EXPECT_TRUE(bt.readBinary((maps / "map.bt").string()));
  EXPECT_EQ(YAML::LoadFile((maps / "map.yaml").string())["image"].as<std::string>(), "map.pgm");
  for (const char* name : {"map.ot", "map.pgm", "map.png"}) EXPECT_TRUE(std::filesystem::exists(maps / name)) << name;

  polarslam::goal_t goal{};
  goal.utime = 8'000'000;
  goal.x = 5.0;
  goal.y = 0.8;
  goal.theta = std::numeric_limits<double>::quiet_NaN();
  lcm.publish("GOAL", &goal);
  ASSERT_TRUE(handleUntil(lcm, 10s, [&] { return listener.planned_path.has_value(); }));
  std::vector<Vec2> waypoints;
  ASSERT_EQ(fromLcm(*listener.planned_path, waypoints), "");
  EXPECT_EQ(listener.planned_path->goal_utime, goal.utime);
  EXPECT_EQ(listener.planned_path->goal_exact, 1);
  ASSERT_GE(waypoints.size(), 3u);  // around the doorway jamb
  EXPECT_NEAR((waypoints.front() - Vec2(1.0, 0.8)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((waypoints.back() - Vec2(5.0, 0.8)).norm(), 0.0, 1e-9);
  for (size_t i = 1; i < waypoints.size(); ++i)
    for (double t = 0; t <= 1.0; t += 0.01)
      EXPECT_GT(test::distanceToWalls(world, waypoints[i - 1] + t * (waypoints[i] - waypoints[i - 1])), 0.3);

  handleUntil(lcm, 1500ms, [&] { return listener.grid_rejected >= 3; });
  EXPECT_GE(listener.grid_rejected, 3) << "the malformed SCAN_ANCHORS message and the two folders out are counted";
  EXPECT_FALSE(std::filesystem::exists("/tmp/polarslam-grid-request-escape"));
  EXPECT_FALSE(std::filesystem::exists(dir / "escape"));
  grid.signal(SIGINT);
  ASSERT_TRUE(grid.waitFor(10s));
  EXPECT_EQ(grid.exitCode(), 0);
  std::filesystem::remove_all(dir);
}

// --source psm-slam: reference scans (LASER paired with PSM_SLAM_ANCHORS, in either order) placed
// by PSM_SLAM_GRAPH; GRID_MAP follows every graph change, and the last graph on exit wins.
TEST(GridProcess, GridFromThePoseGraphFollowsTheGraphOnGridMap) {
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-it-grid-psm-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::vector<GridSlice> grids;
  struct GridListener {
    std::vector<GridSlice>* grids;
    void onGrid(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      polarslam::grid_map_t msg;
      GridSlice slice;
      if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0 && fromLcm(msg, slice).empty())
        grids->push_back(slice);
    }
  } listener{&grids};
  lcm.subscribe("GRID_MAP", &GridListener::onGrid, &listener);
  ChildProcess grid({binPath("polarslam-grid"), "--source", "psm-slam", "--out", (dir / "maps").string(), "--period",
                     "0.2", "--config", sourcePath("config/psm-slam.yaml")},
                    (dir / "grid.log").string());
  std::this_thread::sleep_for(700ms);  // let it join the group

  const World world = test::twoRoomWorld();
  const std::vector<Pose2> poses = test::twoRoomPoses();
  PoseGraph truth_graph, wrong_graph;
  const Pose2 shift(0.5, -0.3, 0.1);  // a graph before its loop closure: everything off
  for (size_t k = 0; k < poses.size(); ++k) {
    const int64_t utime = 1'000'000 * static_cast<int64_t>(k + 1);
    truth_graph.addNode({static_cast<int64_t>(k), utime, poses[k]});
    wrong_graph.addNode({static_cast<int64_t>(k), utime, shift * poses[k]});
    polarslam::laser_scan_t scan = toLcm(test::castScan(world, poses[k], 361, 2 * std::numbers::pi, utime));
    scan.seq = static_cast<int64_t>(k);
    const polarslam::anchored_pose_t anchor = toLcm(AnchoredPose{utime, static_cast<int64_t>(k), Pose2(), true},
                                                    static_cast<int64_t>(k));
    if (k % 2) {
      lcm.publish("LASER", &scan);
      lcm.publish("PSM_SLAM_ANCHORS", &anchor);
    } else {
      lcm.publish("PSM_SLAM_ANCHORS", &anchor);
      lcm.publish("LASER", &scan);
    }
    std::this_thread::sleep_for(20ms);
  }
  auto occupiedNearWalls = [&](const GridSlice& g) {
    int occupied = 0, near = 0;
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x)
        if (g.occupied(x, y)) {
          ++occupied;
          near += test::distanceToWalls(world, g.cellCenter(x, y)) < 0.1;
        }
    return occupied > 0 ? static_cast<double>(near) / occupied : 0.0;
  };
  lcm.publish("PSM_SLAM_GRAPH", &static_cast<const polarslam::pose_graph_t&>(toLcm(wrong_graph, 7'000'000, 0, 0, 0.0)));
  ASSERT_TRUE(handleUntil(lcm, 10s, [&] { return !grids.empty(); })) << "no GRID_MAP; see " << (dir / "grid.log");
  EXPECT_LT(occupiedNearWalls(grids.back()), 0.5) << "placed by the shifted graph";
  const size_t before = grids.size();
  lcm.publish("PSM_SLAM_GRAPH", &static_cast<const polarslam::pose_graph_t&>(toLcm(truth_graph, 7'000'000, 1, 1, 0.0)));
  ASSERT_TRUE(handleUntil(lcm, 10s, [&] { return grids.size() > before; }));
  EXPECT_GT(occupiedNearWalls(grids.back()), 0.95) << "re-placed by the corrected graph";
  grid.signal(SIGINT);
  ASSERT_TRUE(grid.waitFor(10s));
  EXPECT_EQ(grid.exitCode(), 0);
  octomap::OcTree bt(0.1);
  EXPECT_TRUE(bt.readBinary((dir / "maps" / "map.bt").string())) << "map files written on exit";
  std::filesystem::remove_all(dir);
}

TEST(SimProcess, FollowsAPlannedPathToItsGoal) {
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good()) << "LCM UDP multicast unavailable: run the tests through scripts/with-netns";
  const auto dir = std::filesystem::temp_directory_path() / ("polarslam-it-follow-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  Listener listener;
  lcm.subscribe("GROUND_TRUTH", &Listener::onTruth, &listener);
  // No SLAM here: the sim locates the path in its start frame from its own true pose.
  ChildProcess sim({binPath("polarslam-sim"), "--world", sourcePath("config/worlds/room.yaml"), "--robot",
                    sourcePath("config/robots/default.yaml"), "--speed", "4", "--seconds", "120", "--path-channel",
                    "PLANNED_PATH", "--pose-channel", ""},
                   (dir / "sim.log").string());
  ASSERT_TRUE(handleUntil(lcm, 10s, [&] { return listener.truth.has_value(); }));
  const Pose2 start = loadWorld(sourcePath("config/worlds/room.yaml")).start.value();
  const Vec2 world_goal(0.8, 1.2);
  std::vector<Vec2> map_path;
  for (const Vec2& w : {listener.truth->translation(), Vec2(0.6, 0.0), world_goal})
    map_path.push_back(start.inverseTransform(w));
  const polarslam::path_t plan = toLcmPath(map_path, 1, true, nowUtime(), 0);
  lcm.publish("PLANNED_PATH", &plan);
  auto atGoal = [&] { return listener.truth && (listener.truth->translation() - world_goal).norm() < 0.15; };
  ASSERT_TRUE(handleUntil(lcm, 30s, atGoal)) << "robot at " << listener.truth->translation().transpose();
  handleUntil(lcm, 1500ms, [] { return false; });
  EXPECT_TRUE(atGoal()) << "the robot stays at the goal";
  sim.signal(SIGINT);
  ASSERT_TRUE(sim.waitFor(10s));
  EXPECT_EQ(sim.exitCode(), 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace polarslam
