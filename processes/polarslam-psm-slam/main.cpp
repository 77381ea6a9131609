// polarslam-psm-slam: SLAM with polar scan matching. LASER + ODOMETRY → PSM_SLAM_POSE (pose_t,
// frame "map", one per scan, with covariance), PSM_SLAM_ANCHORS (anchored_pose_t, the same pose
// relative to its reference scan) and PSM_SLAM_GRAPH (pose_graph_t: after every optimisation,
// when the graph has otherwise changed at most every --graph-period seconds, and once more on
// exit after a final optimisation) and, on exit, PSM_SLAM_PATH (path_t: the final trajectory, one
// pose per scan, what `polarslam run` writes to trajectory.tum). With --save-map M it saves its map (core/map/map_store.hpp)
// on every SAVE_MAP request (map_request_t) and on exit; with --load-map M it localises in a saved
// map (--mode localize: poses only, no anchors or graph) or maps on from it (--mode continue). A
// thin shell over core/pipeline/psm_slam_session.hpp, what `polarslam run --pipeline psm-slam`
// runs with the same options and --config file.
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "common/program_info.hpp"
#include "pipeline/pipelines.hpp"
#include "common/lcm_convert.hpp"
#include "common/process_context.hpp"
#include "common/path_messages.hpp"
#include "common/pose_graph_message.hpp"
#include "common/saved_map_options.hpp"
#include "map/map_store.hpp"
#include "pipeline/psm_slam_session.hpp"
#include "polarslam/map_request_t.hpp"
#include "slam/psm_slam.hpp"

using namespace polarslam;

namespace {

struct Channels {
  std::string laser = "LASER", odometry = "ODOMETRY", pose = "PSM_SLAM_POSE", anchors = "PSM_SLAM_ANCHORS",
              graph = "PSM_SLAM_GRAPH", path = "PSM_SLAM_PATH", save_map = "SAVE_MAP";
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

/// Moves a snapshot that cannot be resumed out of the way, keeping it for a person to look at.
void setSnapshotAside(const std::string& dir, const std::string& why, const std::string& suffix) {
  std::error_code ec;
  std::filesystem::remove_all(dir + suffix, ec);
  std::filesystem::rename(dir, dir + suffix, ec);
  std::cerr << "polarslam-psm-slam: warning: snapshot " << dir << " " << why << "; kept as " << dir + suffix << "\n";
}

/// The crash-recovery snapshot to resume from, if `dir` holds one of this launch; a damaged or
/// stale one is moved aside with a warning and the process starts from its journal alone.
std::optional<SessionSnapshot> restorableSnapshot(const std::string& dir, const SavedMapOptions& options) {
  try {
    std::optional<SessionSnapshot> snapshot = readSessionSnapshot(dir, options);
    if (snapshot && snapshot->resume.value("launch", std::string()) != InputJournal::currentLaunchId()) {
      setSnapshotAside(dir, "belongs to another launch (a reused run folder?)", ".stale");
      return std::nullopt;
    }
    if (snapshot) std::cerr << "polarslam-psm-slam: resuming from snapshot " << dir << "\n";
    return snapshot;
  } catch (const MapFormatError& e) {
    setSnapshotAside(dir, std::string("is damaged (") + e.what() + ")", ".damaged");
    return std::nullopt;
  }
}

/// The session, resumed from `snapshot` where that can be; a snapshot that is readable but names
/// what its map lacks (a filter of scans it does not hold) is set aside like a damaged one.
std::unique_ptr<PsmSlamSession> startSession(const PsmSlamEstimatorConfig& config, const SavedMapOptions& options,
                                             std::optional<SessionSnapshot>& snapshot, const std::string& snapshot_dir) {
  if (snapshot) {
    try {
      auto session = std::make_unique<PsmSlamSession>(config, snapshot->options);
      snapshot->options.loaded_map.reset();  // the session holds its own copy
      return session;
    } catch (const std::invalid_argument& e) {
      setSnapshotAside(snapshot_dir, std::string("cannot be resumed (") + e.what() + ")", ".damaged");
      snapshot.reset();
    }
  }
  return std::make_unique<PsmSlamSession>(config, options);
}

/// One line of what the run did, from its report figures.
std::string exitSummary(const nlohmann::json& report) {
  auto count = [](const nlohmann::json& section, const char* key) { return std::to_string(section.value(key, 0)); };
  std::string line;
  if (report.contains("localization")) {
    const nlohmann::json& l = report["localization"];
    line = "localisation: " + count(l, "fixes") + " fixes, " + count(l, "losses") + " losses";
    if (l.value("first_fix_scan", int64_t{-1}) >= 0) line += ", first fix at scan " + count(l, "first_fix_scan");
    line += "; ";
  }
  if (report.contains("psm_slam")) {
    const nlohmann::json& p = report["psm_slam"];
    line += count(p, "scans") + " scans, " + count(p, "keyframes") + " reference scans, " + count(p, "loop_closures") +
            " loop closures, " + count(p, "optimizations") + " optimisations";
    if (p.contains("refinement") && p["refinement"].value("pairs", 0) > 0)
      line += ", refinement: " + count(p["refinement"], "edges") + " edges of " + count(p["refinement"], "pairs") +
              " pairs matched (" + count(p["refinement"], "background_rounds") + " rounds after loop closures)";
  }
  return line;
}

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
  app.add_option("--path-channel", channels.path, "channel of the final trajectory, on exit (path_t)")->capture_default_str();
  std::string save_map;
  app.add_option("--save-map", save_map,
                 "save the map (pose graph, reference scans, grid, parameters) to this folder on exit and on "
                 "every SAVE_MAP request, replacing the older map only once the new one is complete");
  app.add_option("--save-map-channel", channels.save_map, "channel of the save requests (map_request_t)")
      ->capture_default_str();
  SavedMapCli saved_map;
  saved_map.add(app);
  JournalOptions journal;
  addJournalOptions(app, journal);
  double snapshot_period = 60.0;
  app.add_option("--snapshot-period", snapshot_period,
                 "with --journal: s of stream time between snapshots of the map and pose (JOURNAL.snapshot, a saved "
                 "map); each cuts the journal, so a restart replays at most this much (0: never, the journal "
                 "keeps the whole run)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  addPrintConfigFlag(app, [&] { return effectiveConfigYaml("psm-slam", {"fused", config}); });
  CLI11_PARSE(app, argc, argv);

  try {
    const SavedMapOptions map_options = saved_map.resolve(save_map);
    const bool snapshots = !journal.path.empty() && snapshot_period > 0.0;
    const std::string snapshot_dir = journal.path + ".snapshot";
    std::optional<SessionSnapshot> snapshot = snapshots ? restorableSnapshot(snapshot_dir, map_options) : std::nullopt;
    const std::unique_ptr<PsmSlamSession> session_owner =
        startSession(loadPsmSlamEstimatorConfig(config), map_options, snapshot, snapshot_dir);
    PsmSlamSession& session = *session_owner;
    if (snapshot && snapshot->last_odometry) session.onOdometry(*snapshot->last_odometry);
    int64_t last_snapshot_utime = snapshot ? snapshot->resume.value("utime", int64_t{0}) : 0;
    auto save = [&](const char* why) {
      try {
        session.saveMapNow();
        std::cerr << "polarslam-psm-slam: map saved to " << session.saveMapFolder() << " (" << why << ")\n";
        return true;
      } catch (const std::exception& e) {
        std::cerr << "polarslam-psm-slam: map not saved (" << why << "): " << e.what() << "\n";
        return false;
      }
    };
    ProcessContext context("polarslam-psm-slam", process_options);
    context.enableJournal(journal);
    if (snapshot)
      context.resumeFromSnapshot(snapshot->resume.value("generation", uint64_t{0}),
                                 snapshot->resume.value("journal_events", size_t{0}));
    auto snapshotIfDue = [&](int64_t utime) {
      if (!snapshots || !session.canSnapshot()) return;
      if (last_snapshot_utime == 0) last_snapshot_utime = utime;
      if (context.replaying() || utime - last_snapshot_utime < static_cast<int64_t>(snapshot_period * 1e6)) return;
      try {
        session.writeSnapshot(snapshot_dir, {{"generation", context.journalGeneration() + 1},
                                             {"journal_events", context.journalEvents()},
                                             {"launch", InputJournal::currentLaunchId()},
                                             {"utime", utime}});
        context.cutJournal();
        last_snapshot_utime = utime;
      } catch (const std::exception& e) {
        context.reject(std::string("snapshot not written (the journal keeps growing): ") + e.what());
      }
    };
    GraphPublisher graph(context, channels.graph, graph_period);
    int64_t pose_seq = 0, anchor_seq = 0, last_utime = 0;
    auto publishGraph = [&](bool force) {
      if (const PsmSlam* slam = session.slam()) graph.publishIfDue(*slam, last_utime, force);
    };
    context.subscribeConverted<polarslam::laser_scan_t, LaserScan>(channels.laser, [&](LaserScan& scan) {
      const PsmSlamScanOutput r = session.onLaser(scan);
      if (!r.usable) context.reject("laser: too few usable readings to match");
      context.publish(channels.pose, toLcm(r.pose, "map", pose_seq++));
      if (r.anchor) context.publish(channels.anchors, toLcm(*r.anchor, anchor_seq++));
      if (r.graph_changed) graph.changed();
      last_utime = scan.utime;
      publishGraph(r.optimized);
      snapshotIfDue(scan.utime);
      context.handled();
    });
    context.subscribeConverted<polarslam::odometry_t, OdometryReading>(channels.odometry, [&](OdometryReading& reading) {
      session.onOdometry(reading);
      context.handled();
    });
    context.subscribe<polarslam::map_request_t>(channels.save_map, [&](const polarslam::map_request_t&) {
      if (!session.savesMap()) return context.reject("SAVE_MAP: no --save-map folder");
      if (!save("request")) return context.reject("SAVE_MAP: saving failed");
      context.handled();
    });
    context.run({}, [&] { publishGraph(false); });
    if (!session.started()) return 0;
    nlohmann::json report;
    bool saved = true;
    try {
      report = session.finish();  // the final optimisation, and the map saved with --save-map
      if (session.savesMap()) std::cerr << "polarslam-psm-slam: map saved to " << session.saveMapFolder() << " (exit)\n";
    } catch (const MapFormatError& e) {  // the optimisation has run: its graph still goes out
      std::cerr << "polarslam-psm-slam: map not saved (exit): " << e.what() << "\n";
      saved = false;
    }
    graph.changed();
    publishGraph(true);
    context.publish(channels.path, toLcmPath(session.finalTrajectory(), last_utime, 0));
    std::cerr << "polarslam-psm-slam: " << exitSummary(report) << "\n";
    if (!saved) return 1;
  } catch (const std::exception& e) {
    std::cerr << "polarslam-psm-slam: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
