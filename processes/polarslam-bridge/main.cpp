// polarslam-bridge: watch polarslam live. Subscribes to the polarslam channels and serves them
// with the Foxglove WebSocket protocol (foxglove.websocket.v1, JSON encoding, foxglove.* schemas)
// on --bind:--port (127.0.0.1:8765): Foxglove or Lichtblick connect to ws://localhost:8765.
// The same port serves a built-in map page over plain HTTP (http://localhost:8765/) that draws
// the same messages; a click on its map publishes a GOAL unless --read-only.
// The network runs on its own thread (bridge_server.hpp); LCM handling never waits for a client.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "bridge_server.hpp"
#include "common/foxglove_messages.hpp"
#include "common/lcm_convert.hpp"
#include "common/path_messages.hpp"
#include "common/pose_trail.hpp"
#include "common/pose_graph_message.hpp"
#include "common/process_context.hpp"
#include "common/program_info.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/process_status_t.hpp"

using namespace polarslam;
using Json = nlohmann::json;

namespace {

struct Channels {
  std::string laser = "LASER", odometry = "ODOMETRY", grid_map = "GRID_MAP", psm_grid_map = "PSM_GRID_MAP",
              slam_pose = "SLAM_POSE", psm_slam_pose = "PSM_SLAM_POSE", ground_truth = "GROUND_TRUTH",
              slam_map = "SLAM_MAP", graph = "PSM_SLAM_GRAPH", planned_path = "PLANNED_PATH", grid_path = "GRID_PATH",
              goal = "GOAL", tf_pose = "SLAM_POSE";
};

struct Options {
  ServerOptions server;
  Channels channels;
  bool read_only = false;
  double trajectory_period = 0.5;  ///< s between trajectory messages per pose channel
};

constexpr const char* kTransformTopic = "/tf";
constexpr const char* kLogTopic = "/log";
constexpr const char* kStatusChannel = "PROCESS_STATUS";

class Bridge {
 public:
  Bridge(ProcessContext& context, Options options) : context_(context), o_(std::move(options)) {
    const Channels& c = o_.channels;
    for (const std::string& grid : {c.grid_map, c.psm_grid_map}) addTopic(grid, "foxglove.Grid");
    addTopic(c.laser, "foxglove.LaserScan");
    for (const std::string& pose : {c.slam_pose, c.psm_slam_pose, c.ground_truth}) {
      addTopic(pose, "foxglove.PoseInFrame");
      addTopic(trajectoryTopic(pose), "foxglove.PosesInFrame");
      trajectories_.emplace(pose, PoseTrail());
    }
    for (const std::string& path : {c.planned_path, c.grid_path}) addTopic(path, "foxglove.PosesInFrame");
    addTopic(kTransformTopic, "foxglove.FrameTransform");
    for (const std::string& scene : {c.slam_map, c.graph}) addTopic(scene, "foxglove.SceneUpdate");
    addTopic(kLogTopic, "foxglove.Log");
    addTopic(kStatusChannel, "polarslam.ProcessStatus");
    if (!o_.read_only) o_.server.publish_topics = {c.goal};
    o_.server.metadata = {{"goal_topic", o_.read_only ? "" : c.goal},   {"laser_topic", c.laser},
                          {"grid_topics", c.grid_map + "," + c.psm_grid_map},
                          {"pose_topics", c.slam_pose + "," + c.psm_slam_pose + "," + c.ground_truth},
                          {"scene_topics", c.slam_map + "," + c.graph}, {"path_topic", c.planned_path},
                          {"transform_topic", kTransformTopic},         {"log_topic", kLogTopic},
                          {"status_topic", kStatusChannel}};
    server_ = std::make_unique<BridgeServer>(o_.server, table_);
  }

  static std::string trajectoryTopic(const std::string& pose_channel) { return pose_channel + "/trajectory"; }

  void start() { server_->start(); }

  void subscribe() {
    const Channels& c = o_.channels;
    context_.subscribeConverted<polarslam::laser_scan_t, LaserScan>(c.laser, [this](LaserScan& scan) { onLaser(scan); });
    context_.subscribeConverted<polarslam::odometry_t, OdometryReading>(c.odometry,
                                                                        [this](OdometryReading& o) { onOdometry(o); });
    for (const std::string& grid : {c.grid_map, c.psm_grid_map})
      context_.subscribe<polarslam::grid_map_t>(grid, [this, grid](const auto& msg) { onGrid(grid, msg); });
    for (const std::string& pose : {c.slam_pose, c.psm_slam_pose, c.ground_truth})
      context_.subscribe<polarslam::pose_t>(pose, [this, pose](const auto& msg) { onPose(pose, msg); });
    context_.subscribeConverted<polarslam::slam_map_t, FeatureMap>(c.slam_map, [this](FeatureMap& map) {
      send(o_.channels.slam_map, [&] { return foxglove::featureMapScene(map); });
    });
    context_.subscribe<polarslam::pose_graph_t>(c.graph, [this](const auto& msg) { onGraph(msg); });
    for (const std::string& path : {c.planned_path, c.grid_path})
      context_.subscribe<polarslam::path_t>(path, [this, path](const auto& msg) { onPath(path, msg); });
    context_.subscribe<polarslam::process_status_t>(kStatusChannel, [this](const auto& msg) { onStatus(msg); });
  }

  void tick() {
    handleServerEvents();
    const auto now = std::chrono::steady_clock::now();
    if (now < next_trajectories_) return;
    next_trajectories_ = now + std::chrono::milliseconds(static_cast<int64_t>(o_.trajectory_period * 1000.0));
    for (auto& [channel, trajectory] : trajectories_)
      if (trajectory.takeChanged())
        send(trajectoryTopic(channel),
             [&] { return foxglove::posesInFrame(trajectory.poses(), trajectory.utime(), trajectory.frame()); });
  }

  void stop() { server_->stop(); }

 private:
  void addTopic(const std::string& topic, const std::string& schema) {
    if (topic.empty() || table_.find(topic)) throw std::invalid_argument("topic '" + topic + "' is empty or used twice");
    table_.add(topic, schema);
  }

  static uint64_t nowNanoseconds() { return static_cast<uint64_t>(nowUtime()) * 1000u; }

  /// `build` makes the message, only when a client has subscribed to `topic`: without viewers the
  /// bridge costs next to nothing. `received_ns`: when the LCM message arrived (the receive time
  /// clients see; latency is measured from it).
  template <typename Build>
  void send(const std::string& topic, Build build, uint64_t received_ns = nowNanoseconds()) {
    context_.handled();
    const uint32_t channel = *table_.find(topic);
    if (server_->subscribed(channel)) server_->broadcast(channel, received_ns, build().dump());
  }

  void onLaser(const LaserScan& scan) {
    const uint64_t received = nowNanoseconds();
    send(kTransformTopic,
         [&] { return foxglove::frameTransform(scan.laser_pose, scan.utime, foxglove::kBaseFrame, foxglove::kLaserFrame); },
         received);
    send(o_.channels.laser, [&] { return foxglove::laserScan(scan); }, received);
  }

  void onOdometry(const OdometryReading& odometry) {
    odometry_ = odometry.pose;
    send(kTransformTopic, [&] { return foxglove::frameTransform(odometry.pose, odometry.utime, "odom", foxglove::kBaseFrame); });
  }

  void onGrid(const std::string& channel, const polarslam::grid_map_t& msg) {
    GridSlice slice;
    if (const std::string why = fromLcm(msg, slice); !why.empty()) return context_.reject(why);
    if (!context_.checkSequence(channel, msg.seq)) return;
    send(channel, [&] { return foxglove::grid(slice, msg.utime, msg.frame.empty() ? "map" : msg.frame); });
  }

  void onPose(const std::string& channel, const polarslam::pose_t& msg) {
    PoseStamped pose;
    if (const std::string why = fromLcm(msg, pose); !why.empty()) return context_.reject(why);
    if (!context_.checkSequence(channel, msg.seq)) return;
    const std::string frame = msg.frame.empty() ? "map" : msg.frame;
    send(channel, [&] { return foxglove::poseInFrame(pose, frame); });
    trajectories_[channel].add(pose, frame);
    // One estimator places odom in the map (a frame has one parent): map→odom = pose ⊕ odometry⁻¹.
    if (channel == o_.channels.tf_pose && odometry_)
      send(kTransformTopic, [&] { return foxglove::frameTransform(pose.pose * odometry_->inverse(), pose.utime, frame, "odom"); });
  }

  void onGraph(const polarslam::pose_graph_t& msg) {
    PoseGraph graph;
    if (const std::string why = fromLcm(msg, graph); !why.empty()) return context_.reject(why);
    send(o_.channels.graph, [&] { return foxglove::poseGraphScene(graph, msg.utime); });
  }

  void onPath(const std::string& channel, const polarslam::path_t& msg) {
    std::vector<Vec2> points;
    if (const std::string why = fromLcm(msg, points); !why.empty()) return context_.reject(why);
    send(channel, [&] { return foxglove::posesInFrame(headingsAlong(points), msg.utime, msg.frame.empty() ? "map" : msg.frame); });
  }

  void onStatus(const polarslam::process_status_t& msg) {
    if (msg.name.empty() || msg.state.empty()) return context_.reject("process status: empty name or state");
    foxglove::ProcessState s{msg.utime,         msg.name,         msg.host,         msg.state,       msg.pid,
                             msg.restarts,      msg.messages_handled, msg.messages_rejected, msg.messages_dropped,
                             msg.cpu_percent,   msg.rss_mb};
    send(kStatusChannel, [&] { return foxglove::processStatus(s); });
    std::string& last = process_states_[msg.name + "@" + msg.host + ":" + std::to_string(msg.pid)];
    if (last != msg.state) send(kLogTopic, [&] { return foxglove::processLog(s, last); });
    last = msg.state;
  }

  void handleServerEvents() {
    ServerEvents events = server_->takeEvents();
    for (const std::string& line : events.log) std::cerr << "[polarslam-bridge] " << line << "\n";
    for (const std::string& error : events.errors) context_.reject(error);
    for (uint64_t i = 0; i < events.dropped; ++i) context_.reject("websocket: slow client, oldest queued message dropped");
    for (const foxglove::ClientPublication& p : events.publications) publishGoal(p);
  }

  void publishGoal(const foxglove::ClientPublication& publication) {
    polarslam::goal_t goal{};
    Vec2 position;
    if (const std::string why = foxglove::goalFromJson(publication.payload, position, goal.theta); !why.empty())
      return context_.reject("client " + why);
    goal.utime = nowUtime();
    goal.x = position.x();
    goal.y = position.y();
    context_.publish(o_.channels.goal, goal);
    context_.handled();
    std::cerr << "[polarslam-bridge] goal (" << goal.x << ", " << goal.y << ") published on " << o_.channels.goal << "\n";
  }

  ProcessContext& context_;
  Options o_;
  foxglove::ChannelTable table_;
  std::unique_ptr<BridgeServer> server_;
  std::map<std::string, PoseTrail> trajectories_;
  std::map<std::string, std::string> process_states_;
  std::optional<Pose2> odometry_;
  std::chrono::steady_clock::time_point next_trajectories_{};
};

/// The page installed with the program, or the source tree's when run from the build tree.
std::string defaultPageFolder() {
  const std::string installed = dataPath("web");
  if (std::filesystem::is_directory(installed)) return installed;
  return dataPath("processes/polarslam-bridge/web");
}

void addChannelOptions(CLI::App& app, Channels& c) {
  app.add_option("--laser-channel", c.laser, "laser scans (laser_scan_t) -> foxglove.LaserScan")->capture_default_str();
  app.add_option("--odometry-channel", c.odometry, "odometry (odometry_t) -> /tf odom->base_link")->capture_default_str();
  app.add_option("--grid-map-channel", c.grid_map, "EKF grid (grid_map_t) -> foxglove.Grid")->capture_default_str();
  app.add_option("--psm-grid-map-channel", c.psm_grid_map, "PSM SLAM grid -> foxglove.Grid")->capture_default_str();
  app.add_option("--slam-pose-channel", c.slam_pose, "EKF SLAM pose -> foxglove.PoseInFrame")->capture_default_str();
  app.add_option("--psm-slam-pose-channel", c.psm_slam_pose, "PSM SLAM pose -> foxglove.PoseInFrame")->capture_default_str();
  app.add_option("--ground-truth-channel", c.ground_truth, "simulator ground truth -> foxglove.PoseInFrame")
      ->capture_default_str();
  app.add_option("--slam-map-channel", c.slam_map, "EKF feature map -> foxglove.SceneUpdate")->capture_default_str();
  app.add_option("--graph-channel", c.graph, "PSM SLAM pose graph -> foxglove.SceneUpdate")->capture_default_str();
  app.add_option("--planned-path-channel", c.planned_path, "planned path -> foxglove.PosesInFrame")->capture_default_str();
  app.add_option("--grid-path-channel", c.grid_path, "regenerated scan poses -> foxglove.PosesInFrame")
      ->capture_default_str();
  app.add_option("--goal-channel", c.goal, "where clients' goals are published (goal_t)")->capture_default_str();
  app.add_option("--tf-pose-channel", c.tf_pose, "the pose channel that places odom in map (/tf map->odom)")
      ->capture_default_str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-bridge: polarslam channels over the Foxglove WebSocket protocol, and a built-in map page"};
  addVersionFlag(app);
  Options o;
  std::string url;
  o.server.web_root = defaultPageFolder();
  app.add_option("--bind", o.server.bind, "address to listen on (0.0.0.0: every interface)")->capture_default_str();
  app.add_option("--port", o.server.port, "TCP port for WebSocket and HTTP")->check(CLI::Range(1, 65535))
      ->capture_default_str();
  app.add_flag("--read-only", o.read_only, "clients may not publish (no GOAL from the page or from Foxglove)");
  app.add_option("--web-root", o.server.web_root, "folder of the built-in page")->check(CLI::ExistingDirectory)
      ->capture_default_str();
  app.add_option("--queue", o.server.queue_capacity, "messages queued per client before the oldest is dropped")
      ->check(CLI::Range(1, 100000))->capture_default_str();
  app.add_option("--queue-bytes", o.server.queue_bytes, "bytes queued per client before the oldest message is dropped")
      ->check(CLI::Range(size_t{1024}, size_t{1} << 32))->capture_default_str();
  app.add_option("--max-clients", o.server.max_clients, "connections served at once")->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--trajectory-period", o.trajectory_period, "s between trajectory messages")
      ->check(CLI::Range(0.05, 60.0))->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  addChannelOptions(app, o.channels);
  CLI11_PARSE(app, argc, argv);

  try {
    ProcessContext context("polarslam-bridge", url);
    Bridge bridge(context, o);
    bridge.subscribe();
    bridge.start();
    std::cerr << "[polarslam-bridge] ws://" << o.server.bind << ":" << o.server.port << " (Foxglove, Lichtblick), page http://"
              << o.server.bind << ":" << o.server.port << "/" << (o.read_only ? " (read-only)" : "") << "\n";
    context.run({}, [&] { bridge.tick(); }, std::chrono::milliseconds(50));
    bridge.stop();
  } catch (const std::exception& e) {
    std::cerr << "polarslam-bridge: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
