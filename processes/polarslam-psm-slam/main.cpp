// polarslam-psm-slam: SLAM with polar scan matching. LASER + ODOMETRY → PSM_SLAM_POSE (pose_t,
// frame "map", one per scan, with covariance), PSM_SLAM_ANCHORS (anchored_pose_t, the same pose
// relative to its reference scan) and PSM_SLAM_GRAPH (pose_graph_t: after every optimisation,
// when the graph has otherwise changed at most every --graph-period seconds, and once more on
// exit after a final optimisation). With --save-map M it saves its map (core/map/map_store.hpp)
// on every SAVE_MAP request (map_request_t) and on exit. A thin shell over core/slam/psm_slam.hpp, the class
// `polarslam run --pipeline psm-slam` runs with the same --config file.
#include <CLI/CLI.hpp>

#include <chrono>
#include <iostream>

#include "common/program_info.hpp"
#include "pipeline/pipelines.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "common/pose_graph_message.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "map_saving.hpp"
#include "polarslam/map_request_t.hpp"
#include "slam/psm_slam.hpp"

using namespace polarslam;

namespace {

struct Channels {
  std::string laser = "LASER", odometry = "ODOMETRY", pose = "PSM_SLAM_POSE", anchors = "PSM_SLAM_ANCHORS",
              graph = "PSM_SLAM_GRAPH", save_map = "SAVE_MAP";
};

class GraphPublisher {
 public:
  GraphPublisher(ProcessContext& context, std::string channel, double period_s)
      : context_(context),
        channel_(std::move(channel)),
        period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(period_s))) {}

  void changed() { dirty_ = true; }
  void publishIfDue(const PsmSlam& slam, int64_t utime, bool force = false) {
    const auto now = std::chrono::steady_clock::now();
    if (!dirty_ || (!force && now - last_ < period_)) return;
    context_.publish(channel_, toLcm(slam.graph(), utime, seq_++, static_cast<int32_t>(slam.stats().optimizations),
                                     slam.stats().last_optimization_seconds));
    last_ = now;
    dirty_ = false;
  }

 private:
  ProcessContext& context_;
  std::string channel_;
  std::chrono::steady_clock::duration period_;
  std::chrono::steady_clock::time_point last_{};
  bool dirty_ = false;
  int64_t seq_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-psm-slam: SLAM with polar scan matching, loop closure and pose-graph optimisation"};
  addVersionFlag(app);
  std::string config;
  double graph_period = 1.0;
  Channels channels;
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  app.add_option("--config", config, "PSM SLAM parameters (YAML, e.g. config/psm-slam.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--graph-period", graph_period, "s between PSM_SLAM_GRAPH messages at most")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--laser-channel", channels.laser, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  app.add_option("--odometry-channel", channels.odometry, "channel of the odometry (odometry_t)")->capture_default_str();
  app.add_option("--pose-channel", channels.pose, "channel of the robot poses (pose_t)")->capture_default_str();
  app.add_option("--anchors-channel", channels.anchors, "poses relative to their reference scan")->capture_default_str();
  app.add_option("--graph-channel", channels.graph, "channel of the pose graph (pose_graph_t)")->capture_default_str();
  std::string save_map;
  app.add_option("--save-map", save_map,
                 "save the map (pose graph, reference scans, grid, parameters) to this folder on exit and on "
                 "every SAVE_MAP request, replacing the older map only once the new one is complete");
  app.add_option("--save-map-channel", channels.save_map, "channel of the save requests (map_request_t)")
      ->capture_default_str();
  JournalOptions journal;
  addJournalOptions(app, journal);
  addPrintConfigFlag(app, [&] { return effectiveConfigYaml("psm-slam", {"fused", config}); });
  CLI11_PARSE(app, argc, argv);

  try {
    const PsmSlamEstimatorConfig estimator_config =
        config.empty() ? PsmSlamEstimatorConfig{} : loadPsmSlamEstimatorConfig(config);
    PsmSlam slam(estimator_config.slam);
    LiveMapSaver map_saver(save_map, estimator_config);
    auto save = [&](const char* why) {
      try {
        map_saver.save(slam);
        std::cerr << "polarslam-psm-slam: map saved to " << map_saver.folder() << " (" << why << ")\n";
        return true;
      } catch (const std::exception& e) {
        std::cerr << "polarslam-psm-slam: map not saved (" << why << "): " << e.what() << "\n";
        return false;
      }
    };
    ProcessContext context("polarslam-psm-slam", process_options);
    context.enableJournal(journal);
    GraphPublisher graph(context, channels.graph, graph_period);
    int64_t pose_seq = 0, anchor_seq = 0, last_utime = 0;
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(channels.laser, [&](LaserScan& scan) {
      const PsmSlamScanResult r = slam.addScan(scan);
      if (!r.usable) context.reject("laser: too few usable readings to match");
      context.publish(channels.pose, toLcm(r.pose, "map", pose_seq++));
      context.publish(channels.anchors, toLcm(r.anchor, anchor_seq++));
      map_saver.onScan(scan, r.anchor);
      if (r.new_keyframe || r.loop_closed || r.optimized) graph.changed();
      last_utime = scan.utime;
      graph.publishIfDue(slam, last_utime, r.optimized);
      context.handled();
    });
    context.subscribeConverted<polarslam::odometry_t, OdometryReading>(channels.odometry, [&](OdometryReading& reading) {
      slam.addOdometry(reading);
      context.handled();
    });
    context.subscribe<polarslam::map_request_t>(channels.save_map, [&](const polarslam::map_request_t&) {
      if (!map_saver.enabled()) return context.reject("SAVE_MAP: no --save-map folder");
      if (!save("request")) return context.reject("SAVE_MAP: saving failed");
      context.handled();
    });
    context.run({}, [&] { graph.publishIfDue(slam, last_utime); });
    bool saved = true;
    if (slam.started()) {
      slam.optimize();
      graph.changed();
      graph.publishIfDue(slam, last_utime, true);
      if (map_saver.enabled()) saved = save("exit");
    }
    const PsmSlamStats& s = slam.stats();
    std::cerr << "polarslam-psm-slam: " << s.scans << " scans, " << s.keyframes << " reference scans, "
              << s.loop_closures << " loop closures, " << s.optimizations << " optimisations\n";
    if (!saved) return 1;
  } catch (const std::exception& e) {
    std::cerr << "polarslam-psm-slam: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
