// polarslam-bridge over real LCM and real WebSockets, seen by the clients people use: Foxglove's
// own client library (tests/web/foxglove_client.mjs: advertised schemas against the published
// foxglove.* schemas, grid, scan and pose messages validated, protocol errors answered, 12
// clients at once) and the built-in page in headless Chromium (tests/web/page_test.mjs: the
// canvas shows the map, a click on it publishes GOAL on LCM). The node packages come from
// `npm ci` in tests/web (scripts/test runs it); without them these tests are skipped.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <filesystem>
#include <functional>
#include <map>

#include "child_process.hpp"
#include "common/lcm_convert.hpp"
#include "common/pose_graph_message.hpp"
#include "common/process_context.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::readFile;
using polarslam::testing::sourcePath;

namespace polarslam {
namespace {

namespace fs = std::filesystem;

/// Why the node-driven tests cannot run here, or "" when they can.
std::string nodeUnavailable() {
  if (!fs::is_directory(sourcePath("tests/web/node_modules/@foxglove/ws-protocol")))
    return "tests/web/node_modules is missing: run `npm ci` in tests/web (scripts/test does)";
  if (std::system("node --version >/dev/null 2>&1") != 0) return "node is not installed";
  return {};
}

bool acceptsConnections(uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  close(fd);
  return ok;
}

/// The bridge on `port`, once it listens.
std::unique_ptr<ChildProcess> startBridge(uint16_t port, const fs::path& log, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv = {binPath("polarslam-bridge"), "--port", std::to_string(port)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  auto bridge = std::make_unique<ChildProcess>(argv, log.string());
  for (int i = 0; i < 200 && !acceptsConnections(port); ++i) std::this_thread::sleep_for(50ms);
  return bridge;
}

/// A 10 m × 6 m room at 0.1 m, origin (−2, 1): free inside, walls occupied, the outside unknown.
GridSlice roomGrid() {
  GridSlice slice;
  slice.resolution = 0.1;
  slice.origin = Vec2(-2.0, 1.0);
  slice.width = 100;
  slice.height = 60;
  slice.probability.assign(static_cast<size_t>(slice.width * slice.height), 0.1f);
  for (int y = 0; y < slice.height; ++y)
    for (int x = 0; x < slice.width; ++x) {
      const bool wall = x == 5 || y == 5 || x == slice.width - 6 || y == slice.height - 6;
      const bool outside = x < 5 || y < 5 || x > slice.width - 6 || y > slice.height - 6;
      slice.probability[slice.index(x, y)] = wall ? 0.95f : outside ? std::nanf("") : 0.1f;
    }
  return slice;
}

LaserScan someScan(int64_t utime) {
  LaserScan scan;
  scan.utime = utime;
  scan.angle_min = -M_PI / 2;
  scan.angle_increment = M_PI / 180;
  scan.range_max = 8.1;
  scan.laser_pose = Pose2(0.2, 0.0, 0.0);
  scan.ranges.assign(181, 2.0f);
  scan.ranges[10] = std::nanf("");
  return scan;
}

/// Publishes what the polarslam processes would, one round per call (seq numbers increase).
class FakePipeline {
 public:
  explicit FakePipeline(lcm::LCM& lcm) : lcm_(lcm) {}

  void publishRound() {
    const int64_t utime = 1'700'000'000'000'000 + round_ * 100'000;
    polarslam::laser_scan_t scan = toLcm(someScan(utime));
    scan.seq = round_;
    lcm_.publish("LASER", &scan);
    OdometryReading odometry;
    odometry.utime = utime;
    odometry.seq = round_;
    odometry.pose = Pose2(0.01 * round_, 0.0, 0.0);
    polarslam::odometry_t odo = toLcm(odometry);
    lcm_.publish("ODOMETRY", &odo);
    polarslam::pose_t pose = toLcm(PoseStamped{utime, Pose2(3.0 + 0.01 * round_, 4.0, 0.3), Mat3::Identity() * 1e-3}, "map", round_);
    lcm_.publish("SLAM_POSE", &pose);
    if (round_ % 5 == 0) publishMaps(utime);
    ++round_;
  }

 private:
  void publishMaps(int64_t utime) {
    polarslam::grid_map_t grid = toLcmGridMap(roomGrid(), utime, round_ / 5, "ekf-anchors", 10, true);
    lcm_.publish("GRID_MAP", &grid);
    FeatureMap map;
    map.utime = utime;
    MapFeature line;
    line.kind = MapFeatureKind::Line;
    line.params = Vec3(0.0, 7.0, 0.0);
    line.cov = Mat3::Identity() * 1e-4;
    line.endpoint_a = Vec2(7.0, 1.5);
    line.endpoint_b = Vec2(7.0, 6.5);
    MapFeature point;
    point.kind = MapFeatureKind::Point;
    point.params = Vec3(1.0, 2.0, 0.0);
    point.cov = Mat3::Identity() * 0.01;
    map.features = {line, point};
    polarslam::slam_map_t slam_map = toLcm(map, round_ / 5);
    lcm_.publish("SLAM_MAP", &slam_map);
    PoseGraph graph;
    graph.addNode({0, utime, Pose2(0, 2, 0)});
    graph.addNode({1, utime, Pose2(1, 2, 0)});
    PoseGraphEdge edge;
    edge.from = 0;
    edge.to = 1;
    edge.measurement = Pose2(1, 0, 0);
    graph.addEdge(edge);
    polarslam::pose_graph_t graph_msg = toLcm(graph, utime, round_ / 5, 0, 0.0);
    lcm_.publish("PSM_SLAM_GRAPH", &graph_msg);
    polarslam::process_status_t status{};
    status.utime = utime;
    status.name = "polarslam-fake";
    status.host = "test";
    status.pid = 1;
    status.state = round_ < 20 ? "running" : "crashed";
    lcm_.publish("PROCESS_STATUS", &status);
  }

  lcm::LCM& lcm_;
  int64_t round_ = 0;
};

struct StatusWatch {
  int64_t bridge_rejected = -1;
  std::map<std::string, int64_t> bridge_reject_kinds;
  std::vector<polarslam::goal_t> goals;
  void onStatus(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::process_status_t msg;
    if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || msg.name != "polarslam-bridge") return;
    bridge_rejected = msg.messages_rejected;
    for (int i = 0; i < msg.num_reject_kinds; ++i) bridge_reject_kinds[msg.reject_kinds[i]] = msg.reject_counts[i];
  }
  void onGoal(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    polarslam::goal_t msg;
    if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0) goals.push_back(msg);
  }
};

/// Runs `node script args…` while feeding the bridge (each round also calls `extra`); returns
/// node's exit code and its summary.
int runNodeWhilePublishing(lcm::LCM& lcm, const std::vector<std::string>& node_args, const fs::path& out,
                           nlohmann::json& summary, std::chrono::seconds limit = 90s,
                           const std::function<void(int64_t)>& extra = {}) {
  ChildProcess node(node_args, out.string());
  FakePipeline pipeline(lcm);
  const auto end = std::chrono::steady_clock::now() + limit;
  for (int64_t round = 0; node.running() && std::chrono::steady_clock::now() < end; ++round) {
    pipeline.publishRound();
    if (extra) extra(round);
    lcm.handleTimeout(100);
  }
  if (!node.waitFor(1s)) return -1;
  const std::string text = readFile(out);
  const size_t line = text.rfind("{\"ok\"");
  summary = nlohmann::json::parse(line == std::string::npos ? "{}" : text.substr(line, text.find('\n', line) - line),
                                  nullptr, false);
  std::cout << node_args[1] << ": " << summary.dump() << "\n";
  return node.exitCode();
}

TEST(Bridge, FoxgloveClientsGetTheAdvertisedSchemasAndValidMessages) {
  if (const std::string why = nodeUnavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path dir = fs::temp_directory_path() / ("bridge_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good());
  StatusWatch watch;
  lcm.subscribe("PROCESS_STATUS", &StatusWatch::onStatus, &watch);
  const uint16_t port = 18765;
  auto bridge = startBridge(port, dir / "bridge.log");
  ASSERT_TRUE(acceptsConnections(port)) << readFile(dir / "bridge.log");

  nlohmann::json summary;
  const int code = runNodeWhilePublishing(
      lcm, {"node", sourcePath("tests/web/foxglove_client.mjs"), "--url", "ws://127.0.0.1:" + std::to_string(port),
            "--expect", "GRID_MAP,LASER,SLAM_POSE,/tf,SLAM_MAP,PSM_SLAM_GRAPH,SLAM_POSE/trajectory,/log,PROCESS_STATUS",
            "--clients", "12", "--timeout", "60"},
      dir / "node.log", summary);
  EXPECT_EQ(code, 0) << readFile(dir / "node.log") << readFile(dir / "bridge.log");
  EXPECT_EQ(summary.value("clientsWithLaser", 0), 11);
  EXPECT_GE(summary.value("statusErrors", 0), 4);  // every bad request answered
  EXPECT_TRUE(bridge->running()) << readFile(dir / "bridge.log");
  // The bad requests are counted as rejections in the bridge's PROCESS_STATUS.
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (watch.bridge_rejected < 4 && std::chrono::steady_clock::now() < end) lcm.handleTimeout(100);
  EXPECT_GE(watch.bridge_rejected, 4);
  bridge->signal(SIGINT);
  EXPECT_TRUE(bridge->waitFor(10s));
  EXPECT_EQ(bridge->exitCode(), 0);
  fs::remove_all(dir);
}

TEST(Bridge, ThePageDrawsTheMapAndAClickPublishesAGoal) {
  if (const std::string why = nodeUnavailable(); !why.empty()) GTEST_SKIP() << why;
  if (!fs::exists("/usr/bin/chromium")) GTEST_SKIP() << "/usr/bin/chromium is not installed (scripts/test installs it)";
  const fs::path dir = fs::temp_directory_path() / ("bridge_page_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good());
  StatusWatch watch;
  lcm.subscribe("GOAL", &StatusWatch::onGoal, &watch);
  const uint16_t port = 18766;
  auto bridge = startBridge(port, dir / "bridge.log");
  ASSERT_TRUE(acceptsConnections(port)) << readFile(dir / "bridge.log");

  nlohmann::json summary;
  const int code = runNodeWhilePublishing(
      lcm, {"node", sourcePath("tests/web/page_test.mjs"), "--url", "http://127.0.0.1:" + std::to_string(port) + "/",
            "--timeout", "60"},
      dir / "node.log", summary);
  ASSERT_EQ(code, 0) << readFile(dir / "node.log") << readFile(dir / "bridge.log");
  // The 10 m × 6 m grid fitted to the 900 × 700 canvas covers 95 % of its width: far over a third.
  EXPECT_GT(summary.value("drawn", 0), summary.value("canvasPixels", 0) / 3) << summary.dump();
  EXPECT_GT(summary.value("light", 0), summary.value("drawn", 0) / 2) << summary.dump();  // free space
  EXPECT_GT(summary.value("dark", 0), 500) << summary.dump();                             // the walls
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (watch.goals.empty() && std::chrono::steady_clock::now() < end) lcm.handleTimeout(100);
  ASSERT_EQ(watch.goals.size(), 1u) << readFile(dir / "bridge.log");
  // The middle of the canvas is the middle of the grid: (−2 + 5, 1 + 3).
  EXPECT_NEAR(watch.goals[0].x, 3.0, 0.1);
  EXPECT_NEAR(watch.goals[0].y, 4.0, 0.1);
  EXPECT_TRUE(std::isnan(watch.goals[0].theta));
  fs::remove_all(dir);
}

// A client that stops reading must cost only its own messages: its queue drops the oldest
// (counted in PROCESS_STATUS) while LCM handling and the other clients carry on.
TEST(Bridge, AStalledClientLosesItsOwnMessagesOnlyAndTheDropsAreCounted) {
  if (const std::string why = nodeUnavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path dir = fs::temp_directory_path() / ("bridge_slow_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  lcm::LCM lcm(resolveLcmUrl(""));
  ASSERT_TRUE(lcm.good());
  StatusWatch watch;
  lcm.subscribe("PROCESS_STATUS", &StatusWatch::onStatus, &watch);
  const uint16_t port = 18768;
  auto bridge = startBridge(port, dir / "bridge.log");
  ASSERT_TRUE(acceptsConnections(port));
  // 800 × 800 cells of noise (zlib cannot shrink it): about 850 kB of JSON per message.
  GridSlice big;
  big.resolution = 0.05;
  big.width = big.height = 800;
  uint32_t noise = 12345;
  for (int i = 0; i < big.width * big.height; ++i) {
    noise = noise * 1664525u + 1013904223u;
    big.probability.push_back(static_cast<float>(noise >> 25) / 128.0f);
  }
  nlohmann::json summary;
  const int code = runNodeWhilePublishing(
      lcm, {"node", sourcePath("tests/web/slow_client.mjs"), "--url", "ws://127.0.0.1:" + std::to_string(port), "--seconds", "8"},
      dir / "node.log", summary, 60s, [&](int64_t round) {
        polarslam::grid_map_t grid = toLcmGridMap(big, nowUtime(), 1000 + round, "ekf-anchors", 1, true);
        lcm.publish("PSM_GRID_MAP", &grid);
      });
  ASSERT_EQ(code, 0) << readFile(dir / "node.log");
  EXPECT_GT(summary.value("laserAfterStall", 0), 10) << summary.dump();
  EXPECT_TRUE(bridge->running()) << readFile(dir / "bridge.log");
  const std::string kind = "websocket: slow client, oldest queued message dropped";
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (watch.bridge_reject_kinds[kind] == 0 && std::chrono::steady_clock::now() < end) lcm.handleTimeout(100);
  EXPECT_GT(watch.bridge_reject_kinds[kind], 0) << readFile(dir / "bridge.log");
  fs::remove_all(dir);
}

TEST(Bridge, ReadOnlyRefusesGoalsAndAnswersWithAnError) {
  if (const std::string why = nodeUnavailable(); !why.empty()) GTEST_SKIP() << why;
  const fs::path dir = fs::temp_directory_path() / ("bridge_ro_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  lcm::LCM lcm(resolveLcmUrl(""));
  StatusWatch watch;
  lcm.subscribe("GOAL", &StatusWatch::onGoal, &watch);
  const uint16_t port = 18767;
  auto bridge = startBridge(port, dir / "bridge.log", {"--read-only"});
  ASSERT_TRUE(acceptsConnections(port));
  nlohmann::json summary;
  const int code = runNodeWhilePublishing(
      lcm, {"node", sourcePath("tests/web/publish_goal.mjs"), "--url", "ws://127.0.0.1:" + std::to_string(port)},
      dir / "node.log", summary, 30s);
  EXPECT_EQ(code, 0) << readFile(dir / "node.log");
  EXPECT_FALSE(summary.value("clientPublish", true));
  EXPECT_GE(summary.value("statusErrors", 0), 1);
  for (int i = 0; i < 10; ++i) lcm.handleTimeout(50);
  EXPECT_TRUE(watch.goals.empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace polarslam
