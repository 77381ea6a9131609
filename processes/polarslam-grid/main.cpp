// polarslam-grid: the live occupancy grid, from either SLAM.
//  --source ekf       keeps every LASER scan with its SCAN_ANCHORS and regenerates the scan poses
//                     in the latest SLAM_MAP (thesis §3.7.2);
//  --source psm-slam  keeps PSM SLAM's reference scans (LASER paired with PSM_SLAM_ANCHORS) and
//                     re-places them whenever PSM_SLAM_GRAPH changes (the same idea for a graph).
// After every change, at most every --period seconds, it rebuilds the grid and publishes it on
// GRID_MAP (grid_map_t), plus GRID_PATH (the regenerated poses, ekf) and GRID_STATUS; it writes
// map.{ot,bt,pgm,yaml,png} every --write-period seconds, on GRID_REQUEST and on exit (after a last
// build from the final map or graph). On GOAL it plans on the latest grid from the robot's SLAM
// pose and publishes PLANNED_PATH (map frame), re-planned on every newer grid until the robot is
// there. Building and writing run on a worker thread, so messages keep flowing. The grid code is
// the offline pipelines' (core/grid), so a live run and `polarslam run` give the same map.
#include <CLI/CLI.hpp>

#include <chrono>
#include <future>
#include <iostream>
#include <optional>

#include "common/lcm_convert.hpp"
#include "common/path_messages.hpp"
#include "common/pose_graph_message.hpp"
#include "common/process_context.hpp"
#include "grid/graph_scan_store.hpp"
#include "grid/grid_outputs.hpp"
#include "grid/planner.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;

enum class GridSource { Ekf, PsmSlam };

struct Channels {
  std::string laser = "LASER", anchors = "SCAN_ANCHORS", map = "SLAM_MAP", pose = "SLAM_POSE",
              psm_anchors = "PSM_SLAM_ANCHORS", graph = "PSM_SLAM_GRAPH", request = "GRID_REQUEST", goal = "GOAL",
              grid_map = "GRID_MAP", grid_path = "GRID_PATH", planned_path = "PLANNED_PATH", status = "GRID_STATUS";
};

struct Options {
  GridSource source = GridSource::Ekf;
  std::string out_dir = "grid";
  double period = 1.0;         ///< s between rebuilds (and GRID_MAP messages) while the map changes; 0 = on request
  double write_period = 10.0;  ///< s between file writes (0 = only on GRID_REQUEST and exit)
  double goal_tolerance = 0.2;
  bool compress = true;
  GridOutputOptions grid;
  ScanStoreOptions store;
  PsmSlamMapOptions psm_map;
  PlannerOptions planner;
  Channels channels;
};

Clock::duration secondsToDuration(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

/// One rebuilt grid, whichever SLAM it came from.
struct BuiltGrid {
  OccupancyGrid grid;
  GridSlice slice;
  GridPicture picture;
  int scans = 0;
  std::vector<int64_t> utimes;                  ///< ekf: scan utimes of `regenerated`
  std::vector<RegeneratedPose> regenerated;     ///< ekf only
  RegenerationSummary summary;                  ///< ekf only
  double regenerate_seconds = 0.0, build_seconds = 0.0;
};

struct BuildOutcome {
  std::optional<BuiltGrid> result;
  std::string written_dir, error;  ///< written_dir empty: files not written this time
  double write_seconds = 0.0;
};

BuiltGrid buildFromAnchors(const std::vector<AnchoredScan>& scans, const FeatureMap& map,
                           const GridOutputOptions& options) {
  RegeneratedGrid r = regenerateGrid(scans, map, options);
  GridPicture picture = gridPictureOf(r, map);
  return {std::move(r.grid),   std::move(r.slice), std::move(picture), static_cast<int>(scans.size()),
          std::move(r.utimes), std::move(r.poses), r.summary, r.regenerate_seconds, r.build_seconds};
}

BuiltGrid buildFromGraph(const GraphScanStore& store, const PoseGraph& graph, const GridOptions& options) {
  GraphGrid g = buildGraphGrid(store, graph, options);
  GridPicture picture = graphGridPicture(g, graph);
  return {std::move(g.grid), std::move(g.slice), std::move(picture), static_cast<int>(store.size()), {}, {}, {}, 0.0,
          g.build_seconds};
}

/// Builds with `build` and, when `out_dir` is not empty, writes the files.
BuildOutcome buildAndWrite(const std::function<BuiltGrid()>& build, const std::string& out_dir) {
  BuildOutcome outcome;
  try {
    BuiltGrid built = build();
    if (!out_dir.empty()) {
      const auto start = Clock::now();
      writeGridFiles(out_dir, built.grid, built.slice, built.picture);
      outcome.write_seconds = std::chrono::duration<double>(Clock::now() - start).count();
      outcome.written_dir = out_dir;
    }
    outcome.result = std::move(built);
  } catch (const std::exception& e) {
    outcome.error = e.what();
  }
  return outcome;
}

class GridNode {
 public:
  GridNode(ProcessContext& context, Options options)
      : context_(context), o_(std::move(options)), store_(o_.store), graph_store_(o_.psm_map.all_scans) {}

  void subscribe() {
    const Channels& c = o_.channels;
    if (o_.source == GridSource::Ekf) {
      context_.subscribeConverted<polarslam::laser_scan_t, LaserScan>(c.laser, [this](LaserScan& s) {
        store_.addScan(std::move(s));
        context_.handled();
      });
      context_.subscribeConverted<polarslam::scan_anchors_t, ScanAnchors>(c.anchors, [this](ScanAnchors& a) {
        robot_ = a.pose.pose;
        store_.addAnchors(std::move(a));
        context_.handled();
      });
      context_.subscribeConverted<polarslam::slam_map_t, FeatureMap>(c.map, [this](FeatureMap& m) { onMap(m); });
    } else {
      context_.subscribeConverted<polarslam::laser_scan_t, LaserScan>(c.laser, [this](LaserScan& s) {
        graph_store_.addScan(std::move(s));
        context_.handled();
      });
      context_.subscribeConverted<polarslam::anchored_pose_t, AnchoredPose>(c.psm_anchors, [this](AnchoredPose& a) {
        graph_store_.addAnchor(a);
        context_.handled();
      });
      context_.subscribeConverted<polarslam::pose_graph_t, PoseGraph>(c.graph, [this](PoseGraph& g) { onGraph(g); });
    }
    context_.subscribe<polarslam::pose_t>(c.pose, [this](const auto& msg) { onPose(msg); });
    context_.subscribe<polarslam::grid_request_t>(c.request, [this](const auto& msg) { onRequest(msg); });
    if (!c.goal.empty()) context_.subscribe<polarslam::goal_t>(c.goal, [this](const auto& msg) { onGoal(msg); });
  }

  void tick() {
    collectBuild();
    const auto now = Clock::now();
    if (o_.period > 0.0 && changed() && now >= next_build_) {
      const bool write = o_.write_period > 0.0 && now >= next_write_;
      if (startBuild(write ? o_.out_dir : "")) {
        next_build_ = now + secondsToDuration(o_.period);
        if (write) next_write_ = now + secondsToDuration(o_.write_period);
      }
    }
    if (now >= next_status_) {
      publishStatus();
      next_status_ = now + std::chrono::seconds(1);
    }
  }

  /// Exit work: a last build from the final map or graph, written to the files and published.
  void finish() {
    if (job_.valid()) job_.wait();
    collectBuild();
    if (storedScans() == 0) return;
    if (changed() || written_version_ != built_version_) {
      startBuild(o_.out_dir);
      if (job_.valid()) job_.wait();
      collectBuild();
    }
  }

 private:
  size_t storedScans() const { return o_.source == GridSource::Ekf ? store_.size() : graph_store_.size(); }
  uint64_t dataVersion() const {
    return (o_.source == GridSource::Ekf ? store_.version() : graph_store_.version()) + input_changes_;
  }
  bool changed() const { return storedScans() > 0 && dataVersion() != built_version_; }

  void onMap(FeatureMap& map) {
    map_ = std::move(map);
    robot_ = map_.robot.pose;
    ++input_changes_;
    context_.handled();
  }

  void onGraph(PoseGraph& graph) {
    graph_ = std::move(graph);
    ++input_changes_;
    context_.handled();
  }

  void onPose(const polarslam::pose_t& msg) {
    PoseStamped pose;
    if (const std::string why = fromLcm(msg, pose); !why.empty()) return context_.reject(why);
    robot_ = pose.pose;
    context_.handled();
    if (goal_ && (robot_->translation() - goal_->head<2>()).norm() < o_.goal_tolerance) {
      goal_.reset();
      plan_state_ = "reached";
      publishStatus();
    }
  }

  void onRequest(const polarslam::grid_request_t& msg) {
    context_.handled();
    const std::string dir = msg.out_dir.empty() ? o_.out_dir : msg.out_dir;
    if (job_.valid()) queued_request_ = dir;  // after the running build, with the newest data
    else startBuild(dir);
  }

  void onGoal(const polarslam::goal_t& msg) {
    if (!std::isfinite(msg.x) || !std::isfinite(msg.y) || std::abs(msg.x) > 1e6 || std::abs(msg.y) > 1e6) {
      context_.reject("goal: non-finite or absurd position");
      return;
    }
    context_.handled();
    goal_ = Vec3(msg.x, msg.y, msg.theta);
    goal_utime_ = msg.utime;
    if (slice_) plan();
    else if (!job_.valid() && storedScans() > 0) startBuild("");
    else plan_state_ = "waiting for a grid";
  }

  /// Starts a build of the current data (copied for the worker); false if one is running.
  bool startBuild(const std::string& write_dir) {
    if (job_.valid() || storedScans() == 0) return false;
    building_version_ = dataVersion();
    state_ = "building";
    std::function<BuiltGrid()> build;
    if (o_.source == GridSource::Ekf)
      build = [scans = store_.scans(), map = map_, options = o_.grid] { return buildFromAnchors(scans, map, options); };
    else
      build = [store = graph_store_, graph = graph_, options = gridOptions(o_.psm_map)] {
        return buildFromGraph(store, graph, options);
      };
    job_ = std::async(std::launch::async, buildAndWrite, std::move(build), write_dir);
    return true;
  }

  void collectBuild() {
    if (!job_.valid() || job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    BuildOutcome outcome = job_.get();
    if (outcome.result) {
      built_version_ = building_version_;
      onBuilt(std::move(outcome));
    } else {
      state_ = "failed";
      error_ = outcome.error;
      context_.reject("grid: build or write failed");
      std::cerr << "[polarslam-grid] " << outcome.error << "\n";
    }
    publishStatus();
    if (queued_request_) {
      const std::string dir = *queued_request_;
      queued_request_.reset();
      startBuild(dir);
    }
  }

  void onBuilt(BuildOutcome outcome) {
    BuiltGrid& r = *outcome.result;
    state_ = outcome.written_dir.empty() ? "built" : "written";
    error_.clear();
    if (!outcome.written_dir.empty()) {
      written_dir_ = outcome.written_dir;
      written_utime_ = nowUtime();
      write_seconds_ = outcome.write_seconds;
      written_version_ = built_version_;
    }
    const char* source = o_.source == GridSource::Ekf ? "ekf-anchors" : "psm-graph";
    context_.publish(o_.channels.grid_map, toLcmGridMap(r.slice, nowUtime(), grid_seq_++, source, r.scans, o_.compress));
    if (o_.source == GridSource::Ekf)
      context_.publish(o_.channels.grid_path, toLcmPath(r.utimes, r.regenerated, nowUtime(), path_seq_++));
    slice_ = r.slice;
    last_ = std::move(outcome.result);
    if (goal_) plan();
  }

  void plan() {
    if (!goal_ || !slice_) return;
    if (!robot_) {
      plan_state_ = "failed: no SLAM pose yet";
      return;
    }
    const PlanResult plan = planPath(*slice_, robot_->translation(), goal_->head<2>(), o_.planner);
    plan_length_ = plan.length;
    if (!plan.found) {
      plan_state_ = "failed: " + plan.failure;
    } else {
      plan_state_ = plan.goal_exact ? "planned" : "planned to nearest reachable point";
      context_.publish(o_.channels.planned_path,
                       toLcmPath(plan.waypoints, goal_utime_, plan.goal_exact, nowUtime(), plan_seq_++));
    }
    publishStatus();
  }

  void fillStoreStatus(polarslam::grid_status_t& s) const {
    if (o_.source == GridSource::Ekf) {
      const ScanStoreStatistics& st = store_.statistics();
      s.scans_stored = static_cast<int32_t>(store_.size());
      s.scans_received = st.scans_received;
      s.anchors_received = st.anchors_received;
      s.unpaired_dropped = st.unpaired_dropped;
      s.store_bytes = static_cast<int64_t>(store_.memoryBytes());
    } else {
      const GraphScanStoreStatistics& st = graph_store_.statistics();
      s.scans_stored = static_cast<int32_t>(graph_store_.size());
      s.scans_received = st.scans_received;
      s.anchors_received = st.anchors_received;
      s.unpaired_dropped = st.unpaired_dropped;
    }
  }

  void fillGridStatus(polarslam::grid_status_t& s) const {
    if (!last_) return;
    const BuiltGrid& r = *last_;
    s.regenerated = r.summary.regenerated;
    s.chained = r.summary.chained;
    s.stored = r.summary.stored;
    s.anchors_rejected = r.summary.anchors_rejected;
    s.mean_shift_m = r.summary.mean_shift;
    s.max_shift_m = r.summary.max_shift;
    s.resolution_m = r.slice.resolution;
    s.width_cells = r.slice.width;
    s.height_cells = r.slice.height;
    for (int y = 0; y < r.slice.height; ++y)
      for (int x = 0; x < r.slice.width; ++x) {
        s.occupied_cells += r.slice.occupied(x, y);
        s.free_cells += r.slice.free(x, y);
      }
    s.regenerate_s = r.regenerate_seconds;
    s.build_s = r.build_seconds;
    s.write_s = write_seconds_;
  }

  void publishStatus() {
    polarslam::grid_status_t s{};
    s.utime = nowUtime();
    s.seq = status_seq_++;
    s.state = state_;
    s.error = error_;
    s.out_dir = written_dir_;
    s.written_utime = written_utime_;
    fillStoreStatus(s);
    fillGridStatus(s);
    s.plan_state = plan_state_;
    s.plan_length_m = plan_length_;
    context_.publish(o_.channels.status, s);
  }

  ProcessContext& context_;
  Options o_;
  AnchoredScanStore store_;
  FeatureMap map_;
  GraphScanStore graph_store_;
  PoseGraph graph_;
  uint64_t input_changes_ = 0;  ///< maps and graphs received
  std::optional<Pose2> robot_;
  std::optional<Vec3> goal_;
  int64_t goal_utime_ = 0;

  std::future<BuildOutcome> job_;
  std::optional<std::string> queued_request_;
  uint64_t building_version_ = 0, built_version_ = 0, written_version_ = 0;
  Clock::time_point next_build_{}, next_write_{}, next_status_{};
  std::optional<BuiltGrid> last_;
  std::optional<GridSlice> slice_;

  std::string state_ = "waiting", error_, written_dir_, plan_state_ = "none";
  int64_t written_utime_ = 0;
  double write_seconds_ = 0.0, plan_length_ = 0.0;
  int64_t grid_seq_ = 0, path_seq_ = 0, plan_seq_ = 0, status_seq_ = 0;
};

void addChannelOptions(CLI::App& app, Channels& c) {
  app.add_option("--laser-channel", c.laser)->capture_default_str();
  app.add_option("--anchors-channel", c.anchors, "ekf: scan anchors")->capture_default_str();
  app.add_option("--map-channel", c.map, "ekf: feature map")->capture_default_str();
  app.add_option("--psm-anchors-channel", c.psm_anchors, "psm-slam: anchored poses")->capture_default_str();
  app.add_option("--graph-channel", c.graph, "psm-slam: pose graph")->capture_default_str();
  app.add_option("--pose-channel", c.pose, "robot pose for planning")->capture_default_str();
  app.add_option("--request-channel", c.request)->capture_default_str();
  app.add_option("--goal-channel", c.goal, "\"\" = no planning")->capture_default_str();
  app.add_option("--grid-map-channel", c.grid_map, "grid_map_t after every rebuild")->capture_default_str();
  app.add_option("--grid-path-channel", c.grid_path)->capture_default_str();
  app.add_option("--planned-path-channel", c.planned_path)->capture_default_str();
  app.add_option("--status-channel", c.status)->capture_default_str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-grid: the live occupancy grid from EKF SLAM's anchored scans or PSM SLAM's pose graph"};
  Options o;
  std::string url, source = "ekf", config;
  app.add_option("--source", source, "ekf (SCAN_ANCHORS + SLAM_MAP) | psm-slam (PSM_SLAM_ANCHORS + PSM_SLAM_GRAPH)")
      ->check(CLI::IsMember({"ekf", "psm-slam"}))->capture_default_str();
  app.add_option("--config", config, "psm-slam: the PSM SLAM file (its grid_* keys), e.g. config/psm-slam.yaml")
      ->check(CLI::ExistingFile);
  app.add_option("--out", o.out_dir, "folder for map.{ot,bt,pgm,yaml,png}")->capture_default_str();
  app.add_option("--period", o.period, "s between rebuilds and GRID_MAP messages while the map changes (0 = only on GRID_REQUEST)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--write-period", o.write_period, "s between file writes (0 = only on GRID_REQUEST and exit)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--resolution", o.grid.grid.resolution, "ekf: m per cell")->check(CLI::Range(0.005, 5.0))
      ->capture_default_str();
  app.add_option("--max-range", o.grid.grid.max_range, "ekf: m; longer beams only clear space (0 = laser range_max)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--capacity", o.store.capacity, "ekf: scans kept at most (then thinned)")
      ->check(CLI::Range(2, 10000000))->capture_default_str();
  app.add_option("--min-translation", o.store.min_translation, "ekf: m the robot moves between kept scans")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--robot-radius", o.planner.robot_radius, "m, planner inflation")->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--goal-tolerance", o.goal_tolerance, "m")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_flag("!--no-compress", o.compress, "GRID_MAP cells raw instead of zlib-deflated");
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  addChannelOptions(app, o.channels);
  JournalOptions journal;
  addJournalOptions(app, journal);
  CLI11_PARSE(app, argc, argv);
  o.planner.comfort_distance = std::max(o.planner.comfort_distance, 2.0 * o.planner.robot_radius);

  try {
    o.source = source == "ekf" ? GridSource::Ekf : GridSource::PsmSlam;
    if (o.source == GridSource::PsmSlam && app.count("--pose-channel") == 0) o.channels.pose = "PSM_SLAM_POSE";
    if (!config.empty()) o.psm_map = loadPsmSlamEstimatorConfig(config).map;
    ProcessContext context(o.source == GridSource::Ekf ? "polarslam-grid" : "polarslam-grid-psm", url);
    context.enableJournal(journal);
    GridNode node(context, o);
    node.subscribe();
    context.run({}, [&] { node.tick(); }, std::chrono::milliseconds(100));
    node.finish();
  } catch (const std::exception& e) {
    std::cerr << "polarslam-grid: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
