// polarslam-sim: the simulated robot, publishing LASER, SONAR, ODOMETRY and GROUND_TRUTH over
// LCM in real time (or faster, --speed), until the path ends or --seconds have passed.
// With --path-channel it also follows planned paths (path_t, map frame, e.g. PLANNED_PATH from
// polarslam-grid after a GOAL), located through --pose-channel (the SLAM pose), and keeps running
// after a path ends, waiting for the next one.
#include <CLI/CLI.hpp>

#include <chrono>
#include <iostream>
#include <thread>

#include "common/program_info.hpp"
#include "common/path_messages.hpp"
#include "common/planned_path_driver.hpp"
#include "common/process_context.hpp"
#include "common/sim_channels.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"polarslam-sim: simulated robot publishing sensor data over LCM"};
  addVersionFlag(app);
  std::string world = dataPath("config/worlds/office.yaml"), robot = dataPath("config/robots/default.yaml"), url;
  double seconds = 0.0, speed = 1.0;
  uint64_t seed = 1;
  SensorChannels channels;
  std::string path_channel, pose_channel = "SLAM_POSE";
  app.add_option("--world", world, "world YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--robot", robot, "robot and sensor YAML")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--seconds", seconds, "simulated seconds (0 = until the path ends)")->check(CLI::NonNegativeNumber);
  app.add_option("--speed", speed, "multiple of real time (0 = as fast as possible)")->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--seed", seed, "random seed")->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  app.add_option("--laser-channel", channels.laser, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  app.add_option("--sonar-channel", channels.sonar, "channel of the advanced-sonar cycles (sonar_targets_t)")->capture_default_str();
  app.add_option("--odometry-channel", channels.odometry, "channel of the odometry (odometry_t)")->capture_default_str();
  app.add_option("--ground-truth-channel", channels.ground_truth, "channel of the ground-truth poses (pose_t)")->capture_default_str();
  app.add_option("--path-channel", path_channel, "follow planned paths (path_t, map frame) from this channel, e.g. PLANNED_PATH");
  app.add_option("--pose-channel", pose_channel, "SLAM pose locating the robot in the path's map frame ('' = the true pose in the start frame)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  ProcessContext::installSignalHandlers();  // first: a stop during start-up still ends cleanly
  try {
    ProcessContext context("polarslam-sim", url);
    Simulator sim(loadWorld(world), loadRobotDescription(robot), seed);
    auto sink = makeSimChannels(channels, [&](const std::string& channel, int64_t, const auto& msg) {
      context.publish(channel, msg);
      context.handled();
    });
    PlannedPathDriver driver(sim);
    const bool follow_plans = !path_channel.empty();
    if (follow_plans) {
      context.subscribe<polarslam::path_t>(path_channel, [&](const polarslam::path_t& msg) {
        std::vector<Vec2> waypoints;
        if (const std::string why = fromLcm(msg, waypoints); !why.empty()) return context.reject(why);
        context.handled();
        driver.onPath(std::move(waypoints));
      });
      if (!pose_channel.empty())
        context.subscribe<polarslam::pose_t>(pose_channel, [&](const polarslam::pose_t& msg) {
          PoseStamped pose;
          if (const std::string why = fromLcm(msg, pose); !why.empty()) return context.reject(why);
          driver.onMapPose(pose.pose);
        });
    }
    const auto wall_start = std::chrono::steady_clock::now();
    auto next_status = wall_start;
    const double limit = seconds > 0.0 ? seconds : 1e9;
    while (!ProcessContext::stopRequested() && sim.time() < limit && (follow_plans || !sim.finished())) {
      if (follow_plans) {
        context.lcm().handleTimeout(0);
        if (pose_channel.empty()) driver.useTruePose();
      }
      sim.step(sink);
      if (speed > 0.0) {
        const auto due = wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                          std::chrono::duration<double>(sim.time() / speed));
        std::this_thread::sleep_until(due);
      }
      if (std::chrono::steady_clock::now() >= next_status) {
        context.publishStatus("running");
        next_status = std::chrono::steady_clock::now() + std::chrono::seconds(1);
      }
    }
    context.publishStatus("stopped");
    std::cerr << "polarslam-sim: " << sink.messages() << " messages over " << sim.time() << " s simulated\n";
  } catch (const std::exception& e) {
    std::cerr << "polarslam-sim: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
