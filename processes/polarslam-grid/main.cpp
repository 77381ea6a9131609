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
#include <filesystem>
#include <future>
#include <iostream>
#include <optional>

#include "common/program_info.hpp"
#include "common/lcm_convert.hpp"
#include "common/path_messages.hpp"
#include "common/pose_graph_message.hpp"
#include "common/process_context.hpp"
#include "grid/goal_planner.hpp"
#include "io/safe_path.hpp"
#include "pipeline/live_grid.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;

struct Channels {
  std::string laser = "LASER", anchors = "SCAN_ANCHORS", map = "SLAM_MAP", pose = "SLAM_POSE",
              psm_anchors = "PSM_SLAM_ANCHORS", graph = "PSM_SLAM_GRAPH", request = "GRID_REQUEST", goal = "GOAL",
              grid_map = "GRID_MAP", grid_path = "GRID_PATH", planned_path = "PLANNED_PATH", status = "GRID_STATUS";
};

struct Options {
  LiveGridOptions grid;
  std::string out_dir = "grid";
  double period = 1.0;         ///< s between rebuilds (and GRID_MAP messages) while the map changes; 0 = on request
  double write_period = 10.0;  ///< s between file writes (0 = only on GRID_REQUEST and exit)
  double goal_tolerance = 0.2;
  bool compress = true;
  PlannerOptions planner;
  Channels channels;
};

Clock::duration secondsToDuration(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

struct BuildOutcome {
  std::optional<BuiltGrid> result;
  std::string written_dir, error;  ///< written_dir empty: files not written this time
  double write_seconds = 0.0;
};

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
      : context_(context), o_(std::move(options)), grid_(o_.grid), planner_(o_.planner, o_.goal_tolerance) {}

  void subscribe() {
    const Channels& c = o_.channels;
    context_.subscribeConverted<polarslam::laser_scan_t, LaserScan>(c.laser, [this](LaserScan& s) {
      grid_.addScan(std::move(s));
      context_.handled();
    });
    if (grid_.source() == GridSource::EkfAnchors) {
      context_.subscribeConverted<polarslam::scan_anchors_t, ScanAnchors>(c.anchors, [this](ScanAnchors& a) {
        updateRobot(a.pose.pose);
        grid_.addScanAnchors(std::move(a));
        context_.handled();
      });
      context_.subscribeConverted<polarslam::slam_map_t, FeatureMap>(c.map, [this](FeatureMap& m) {
        updateRobot(m.robot.pose);
        grid_.setFeatureMap(std::move(m));
        context_.handled();
      });
    } else {
      context_.subscribeConverted<polarslam::anchored_pose_t, AnchoredPose>(c.psm_anchors, [this](AnchoredPose& a) {
        grid_.addAnchoredPose(a);
        context_.handled();
      });
      context_.subscribeConverted<polarslam::pose_graph_t, PoseGraph>(c.graph, [this](PoseGraph& g) {
        grid_.setPoseGraph(std::move(g));
        context_.handled();
      });
    }
    context_.subscribe<polarslam::pose_t>(c.pose, [this](const auto& msg) { onPose(msg); });
    context_.subscribe<polarslam::grid_request_t>(c.request, [this](const auto& msg) { onRequest(msg); });
    if (!c.goal.empty()) context_.subscribe<polarslam::goal_t>(c.goal, [this](const auto& msg) { onGoal(msg); });
  }

  void tick() {
    collectBuild();
    const auto now = Clock::now();
    if (o_.period > 0.0 && grid_.changed() && now >= next_build_) {
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
    if (grid_.storedScans() == 0) return;
    if (grid_.changed() || !written_latest_) {
      startBuild(o_.out_dir);
      if (job_.valid()) job_.wait();
      collectBuild();
    }
  }

 private:
  void onPose(const polarslam::pose_t& msg) {
    PoseStamped pose;
    if (const std::string why = fromLcm(msg, pose); !why.empty()) return context_.reject(why);
    context_.handled();
    updateRobot(pose.pose);
  }

  void updateRobot(const Pose2& pose) {
    if (planner_.updateRobot(pose)) publishStatus();
  }

  /// GRID_REQUEST: anyone on the network may send one, so its folder must stay below --out.
  void onRequest(const polarslam::grid_request_t& msg) {
    std::string dir = o_.out_dir;
    if (!msg.out_dir.empty()) {
      std::string why;
      const std::filesystem::path below = pathBelow(o_.out_dir, msg.out_dir, why);
      if (below.empty()) return context_.reject("grid request: folder refused, " + why);
      dir = below.string();
    }
    context_.handled();
    if (job_.valid()) queued_request_ = dir;  // after the running build, with the newest data
    else startBuild(dir);
  }

  void onGoal(const polarslam::goal_t& msg) {
    std::optional<GoalPlan> plan;
    if (const std::string why = planner_.setGoal(Vec2(msg.x, msg.y), msg.utime, plan); !why.empty())
      return context_.reject(why);
    context_.handled();
    if (!planner_.hasGrid() && !job_.valid() && grid_.storedScans() > 0) startBuild("");
    publishPlan(plan);
  }

  /// Starts a build of the current data (copied for the worker); false if one is running.
  bool startBuild(const std::string& write_dir) {
    if (job_.valid() || grid_.storedScans() == 0) return false;
    state_ = "building";
    job_ = std::async(std::launch::async, buildAndWrite, grid_.build(), write_dir);
    return true;
  }

  void collectBuild() {
    if (!job_.valid() || job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    BuildOutcome outcome = job_.get();
    if (outcome.result) {
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
    written_latest_ = !outcome.written_dir.empty();
    if (written_latest_) {
      written_dir_ = outcome.written_dir;
      written_utime_ = nowUtime();
      write_seconds_ = outcome.write_seconds;
    }
    const bool ekf = grid_.source() == GridSource::EkfAnchors;
    context_.publish(o_.channels.grid_map,
                     toLcmGridMap(r.slice, nowUtime(), grid_seq_++, ekf ? "ekf-anchors" : "psm-graph", r.scans, o_.compress));
    if (ekf)
      context_.publish(o_.channels.grid_path, toLcmPath(r.utimes, r.regenerated, nowUtime(), path_seq_++));
    const bool had_goal = planner_.hasGoal();
    const std::optional<GoalPlan> plan = planner_.updateGrid(r.slice);
    last_ = std::move(outcome.result);
    if (had_goal) publishPlan(plan);
  }

  void publishPlan(const std::optional<GoalPlan>& plan) {
    if (plan)
      context_.publish(o_.channels.planned_path,
                       toLcmPath(plan->waypoints, plan->goal_utime, plan->goal_exact, nowUtime(), plan_seq_++));
    publishStatus();
  }

  void fillStoreStatus(polarslam::grid_status_t& s) const {
    const LiveGridCounts c = grid_.counts();
    s.scans_stored = static_cast<int32_t>(c.scans_stored);
    s.scans_received = c.scans_received;
    s.anchors_received = c.anchors_received;
    s.unpaired_dropped = c.unpaired_dropped;
    s.store_bytes = c.store_bytes;
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
    s.plan_state = planner_.state();
    s.plan_length_m = planner_.planLength();
    context_.publish(o_.channels.status, s);
  }

  ProcessContext& context_;
  Options o_;
  LiveGrid grid_;
  GoalPlanner planner_;

  std::future<BuildOutcome> job_;
  std::optional<std::string> queued_request_;
  bool written_latest_ = false;  ///< the files hold the latest build
  Clock::time_point next_build_{}, next_write_{}, next_status_{};
  std::optional<BuiltGrid> last_;

  std::string state_ = "waiting", error_, written_dir_;
  int64_t written_utime_ = 0;
  double write_seconds_ = 0.0;
  int64_t grid_seq_ = 0, path_seq_ = 0, plan_seq_ = 0, status_seq_ = 0;
};

void addChannelOptions(CLI::App& app, Channels& c) {
  app.add_option("--laser-channel", c.laser, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  app.add_option("--anchors-channel", c.anchors, "ekf: scan anchors")->capture_default_str();
  app.add_option("--map-channel", c.map, "ekf: feature map")->capture_default_str();
  app.add_option("--psm-anchors-channel", c.psm_anchors, "psm-slam: anchored poses")->capture_default_str();
  app.add_option("--graph-channel", c.graph, "psm-slam: pose graph")->capture_default_str();
  app.add_option("--pose-channel", c.pose, "robot pose for planning")->capture_default_str();
  app.add_option("--request-channel", c.request, "channel of the grid requests (grid_request_t)")->capture_default_str();
  app.add_option("--goal-channel", c.goal, "\"\" = no planning")->capture_default_str();
  app.add_option("--grid-map-channel", c.grid_map, "grid_map_t after every rebuild")->capture_default_str();
  app.add_option("--grid-path-channel", c.grid_path, "channel of the regenerated scan poses (path_t)")->capture_default_str();
  app.add_option("--planned-path-channel", c.planned_path, "channel of the planned paths (path_t)")->capture_default_str();
  app.add_option("--status-channel", c.status, "channel of the status (grid_status_t)")->capture_default_str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-grid: the live occupancy grid from EKF SLAM's anchored scans or PSM SLAM's pose graph"};
  addVersionFlag(app);
  Options o;
  std::string source = "ekf", config;
  app.add_option("--source", source, "ekf (SCAN_ANCHORS + SLAM_MAP) | psm-slam (PSM_SLAM_ANCHORS + PSM_SLAM_GRAPH)")
      ->check(CLI::IsMember({"ekf", "psm-slam"}))->capture_default_str();
  app.add_option("--config", config, "psm-slam: the PSM SLAM file (its grid_* keys), e.g. config/psm-slam.yaml")
      ->check(CLI::ExistingFile);
  app.add_option("--out", o.out_dir, "folder for map.{ot,bt,pgm,yaml,png}")->capture_default_str();
  app.add_option("--period", o.period, "s between rebuilds and GRID_MAP messages while the map changes (0 = only on GRID_REQUEST)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--write-period", o.write_period, "s between file writes (0 = only on GRID_REQUEST and exit)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--resolution", o.grid.ekf.grid.resolution, "ekf: m per cell")->check(CLI::Range(0.005, 5.0))
      ->capture_default_str();
  app.add_option("--max-range", o.grid.ekf.grid.max_range, "ekf: m; longer beams only clear space (0 = laser range_max)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--capacity", o.grid.store.capacity, "ekf: scans kept at most (then thinned)")
      ->check(CLI::Range(2, 10000000))->capture_default_str();
  app.add_option("--min-translation", o.grid.store.min_translation, "ekf: m the robot moves between kept scans")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--robot-radius", o.planner.robot_radius, "m, planner inflation")->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--goal-tolerance", o.goal_tolerance, "m")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_flag("!--no-compress", o.compress, "GRID_MAP cells raw instead of zlib-deflated");
  ProcessOptions process_options;
  addProcessOptions(app, process_options);
  addChannelOptions(app, o.channels);
  app.add_option("--load-map", o.grid.load_map,
                 "psm-slam: the saved map polarslam-psm-slam continues (--mode continue): its scans are in the grid")
      ->check(CLI::ExistingDirectory);
  JournalOptions journal;
  addJournalOptions(app, journal);
  CLI11_PARSE(app, argc, argv);

  try {
    const bool ekf = source == "ekf";
    o.grid.source = ekf ? GridSource::EkfAnchors : GridSource::PsmGraph;
    if (!ekf && app.count("--pose-channel") == 0) o.channels.pose = "PSM_SLAM_POSE";
    if (!config.empty()) o.grid.psm_map = loadPsmSlamEstimatorConfig(config).map;
    ProcessContext context(ekf ? "polarslam-grid" : "polarslam-grid-psm", process_options);
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
