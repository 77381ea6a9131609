// polarslam-grid: keeps every LASER scan with its SCAN_ANCHORS, regenerates the scan poses in the
// latest SLAM_MAP (thesis §3.7.2) and writes map.{ot,bt,pgm,yaml,png} every --period seconds
// (when something changed) and on GRID_REQUEST; publishes GRID_PATH (the regenerated poses) and
// GRID_STATUS. On GOAL it plans on the latest grid from the robot's SLAM pose and publishes
// PLANNED_PATH (map frame), re-planned on every newer grid until the robot is there; the
// simulator (polarslam-sim --path-channel PLANNED_PATH) or a robot's driver follows it.
// Regeneration, ray casting and file writing run on a worker thread, so messages keep flowing.
#include <CLI/CLI.hpp>

#include <chrono>
#include <future>
#include <iostream>
#include <optional>

#include "common/lcm_convert.hpp"
#include "common/path_messages.hpp"
#include "common/process_context.hpp"
#include "grid/grid_outputs.hpp"
#include "grid/planner.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"
#include "polarslam/scan_anchors_t.hpp"
#include "polarslam/slam_map_t.hpp"

using namespace polarslam;

namespace {

struct Channels {
  std::string laser = "LASER", anchors = "SCAN_ANCHORS", map = "SLAM_MAP", pose = "SLAM_POSE",
              request = "GRID_REQUEST", goal = "GOAL", grid_path = "GRID_PATH", planned_path = "PLANNED_PATH",
              status = "GRID_STATUS";
};

struct Options {
  std::string out_dir = "grid";
  double period = 10.0;  ///< s between automatic regenerations (0 = only on GRID_REQUEST)
  double goal_tolerance = 0.2;
  GridOutputOptions grid;
  ScanStoreOptions store;
  PlannerOptions planner;
  Channels channels;
};

struct BuildOutcome {
  std::optional<RegeneratedGrid> result;
  std::string out_dir, error;
  double write_seconds = 0.0;
};

BuildOutcome buildAndWrite(std::vector<AnchoredScan> scans, FeatureMap map, GridOutputOptions options,
                           std::string out_dir) {
  BuildOutcome outcome;
  outcome.out_dir = out_dir;
  try {
    RegeneratedGrid result = regenerateGrid(scans, map, options);
    const auto start = std::chrono::steady_clock::now();
    writeGridFiles(out_dir, result.grid, result.slice, gridPictureOf(result, map));
    outcome.write_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    outcome.result = std::move(result);
  } catch (const std::exception& e) {
    outcome.error = e.what();
  }
  return outcome;
}

class GridNode {
 public:
  GridNode(ProcessContext& context, Options options) : context_(context), o_(std::move(options)), store_(o_.store) {}

  void subscribe() {
    const Channels& c = o_.channels;
    context_.subscribeConverted<polarslam::laser_scan_t, LaserScan>(c.laser, [this](LaserScan& s) { onLaser(s); });
    context_.subscribeConverted<polarslam::scan_anchors_t, ScanAnchors>(c.anchors,
                                                                        [this](ScanAnchors& a) { onAnchors(a); });
    context_.subscribeConverted<polarslam::slam_map_t, FeatureMap>(c.map, [this](FeatureMap& m) { onMap(m); });
    context_.subscribe<polarslam::pose_t>(c.pose, [this](const auto& msg) { onPose(msg); });
    context_.subscribe<polarslam::grid_request_t>(c.request, [this](const auto& msg) { onRequest(msg); });
    context_.subscribe<polarslam::goal_t>(c.goal, [this](const auto& msg) { onGoal(msg); });
  }

  void tick() {
    collectBuild();
    const auto now = std::chrono::steady_clock::now();
    const bool changed = store_.version() != built_store_version_ || map_seq_ != built_map_seq_;
    if (o_.period > 0.0 && changed && store_.size() > 0 && now >= next_periodic_) {
      startBuild(o_.out_dir);
      next_periodic_ = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double>(o_.period));
    }
    if (now >= next_status_) {
      publishStatus();
      next_status_ = now + std::chrono::seconds(1);
    }
  }

  void finish() {
    if (job_.valid()) job_.wait();
    collectBuild();
  }

 private:
  bool rejectIf(const std::string& why) {
    if (why.empty()) return false;
    context_.reject(why);
    return true;
  }

  void onLaser(LaserScan& scan) {
    store_.addScan(std::move(scan));
    context_.handled();
  }

  void onAnchors(ScanAnchors& anchors) {
    robot_ = anchors.pose.pose;
    store_.addAnchors(std::move(anchors));
    context_.handled();
  }

  void onMap(FeatureMap& map) {
    map_ = std::move(map);
    robot_ = map_.robot.pose;
    ++map_seq_;
    context_.handled();
  }

  void onPose(const polarslam::pose_t& msg) {
    PoseStamped pose;
    if (rejectIf(fromLcm(msg, pose))) return;
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
    else if (!job_.valid() && store_.size() > 0) startBuild(o_.out_dir);
    else plan_state_ = "waiting for a grid";
  }

  void startBuild(const std::string& out_dir) {
    if (job_.valid()) return;
    built_store_version_ = store_.version();
    built_map_seq_ = map_seq_;
    state_ = "building";
    job_ = std::async(std::launch::async, buildAndWrite, store_.scans(), map_, o_.grid, out_dir);
  }

  void collectBuild() {
    if (!job_.valid() || job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    BuildOutcome outcome = job_.get();
    if (outcome.result) {
      RegeneratedGrid& r = *outcome.result;
      state_ = "written";
      error_.clear();
      written_dir_ = outcome.out_dir;
      written_utime_ = nowUtime();
      write_seconds_ = outcome.write_seconds;
      context_.publish(o_.channels.grid_path, toLcmPath(r.utimes, r.poses, nowUtime(), path_seq_++));
      slice_ = r.slice;
      last_ = std::move(outcome.result);
      if (goal_) plan();
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

  void publishStatus() {
    polarslam::grid_status_t s{};
    s.utime = nowUtime();
    s.seq = status_seq_++;
    s.state = state_;
    s.error = error_;
    s.out_dir = written_dir_;
    s.written_utime = written_utime_;
    const ScanStoreStatistics& st = store_.statistics();
    s.scans_stored = static_cast<int32_t>(store_.size());
    s.scans_received = st.scans_received;
    s.anchors_received = st.anchors_received;
    s.unpaired_dropped = st.unpaired_dropped;
    s.store_bytes = static_cast<int64_t>(store_.memoryBytes());
    if (last_) {
      const RegeneratedGrid& r = *last_;
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
    s.plan_state = plan_state_;
    s.plan_length_m = plan_length_;
    context_.publish(o_.channels.status, s);
  }

  ProcessContext& context_;
  Options o_;
  AnchoredScanStore store_;
  FeatureMap map_;
  int64_t map_seq_ = 0;
  std::optional<Pose2> robot_;
  std::optional<Vec3> goal_;
  int64_t goal_utime_ = 0;

  std::future<BuildOutcome> job_;
  std::optional<std::string> queued_request_;
  uint64_t built_store_version_ = 0;
  int64_t built_map_seq_ = -1;
  std::chrono::steady_clock::time_point next_periodic_{}, next_status_{};
  std::optional<RegeneratedGrid> last_;
  std::optional<GridSlice> slice_;

  std::string state_ = "waiting", error_, written_dir_, plan_state_ = "none";
  int64_t written_utime_ = 0;
  double write_seconds_ = 0.0, plan_length_ = 0.0;
  int64_t path_seq_ = 0, plan_seq_ = 0, status_seq_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-grid: occupancy grid from feature-anchored scans, planning to GOAL"};
  Options o;
  std::string url;
  Channels& c = o.channels;
  app.add_option("--out", o.out_dir, "folder for map.{ot,bt,pgm,yaml,png}")->capture_default_str();
  app.add_option("--period", o.period, "s between automatic regenerations (0 = only on request)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--resolution", o.grid.grid.resolution, "m per cell")->check(CLI::Range(0.005, 5.0))->capture_default_str();
  app.add_option("--max-range", o.grid.grid.max_range, "m; longer beams only clear space (0 = laser range_max)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--capacity", o.store.capacity, "scans kept at most (then thinned)")->check(CLI::Range(2, 10000000))
      ->capture_default_str();
  app.add_option("--min-translation", o.store.min_translation, "m the robot moves between kept scans")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--robot-radius", o.planner.robot_radius, "m, planner inflation")->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--goal-tolerance", o.goal_tolerance, "m")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  app.add_option("--laser-channel", c.laser)->capture_default_str();
  app.add_option("--anchors-channel", c.anchors)->capture_default_str();
  app.add_option("--map-channel", c.map)->capture_default_str();
  app.add_option("--pose-channel", c.pose)->capture_default_str();
  app.add_option("--request-channel", c.request)->capture_default_str();
  app.add_option("--goal-channel", c.goal)->capture_default_str();
  app.add_option("--grid-path-channel", c.grid_path)->capture_default_str();
  app.add_option("--planned-path-channel", c.planned_path)->capture_default_str();
  app.add_option("--status-channel", c.status)->capture_default_str();
  JournalOptions journal;
  addJournalOptions(app, journal);
  CLI11_PARSE(app, argc, argv);
  o.planner.comfort_distance = std::max(o.planner.comfort_distance, 2.0 * o.planner.robot_radius);

  try {
    ProcessContext context("polarslam-grid", url);
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
