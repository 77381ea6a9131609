// polarslam run: the whole pipeline offline over an LCM log, as fast as the CPU allows, with the
// same core code the live processes use. Writes trajectory.tum, report.json and plots.
#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "command_registry.hpp"
#include "eval/ate.hpp"
#include "eval/eval_json.hpp"
#include "io/atomic_file.hpp"
#include "plot/plot.hpp"
#include "io/tum.hpp"
#include "offline_log.hpp"
#include "pipeline/pipelines.hpp"
#include "common/saved_map_options.hpp"
#include "pipeline/psm_slam_session.hpp"
#include "map/map_store.hpp"
#include "pipeline/psm_slam_estimator.hpp"

namespace polarslam {
namespace {

struct RunOptions {
  std::string log, pipeline = "odometry", out;
  PipelineOptions pipeline_options;
  SensorChannelNames channels;
  bool print_config = false;
  double max_time_jump_s = 10.0;
  std::string save_map;  ///< psm-slam: folder the map is saved to (core/map/map_store.hpp)
  bool strict = false;    ///< a run without usable laser data is an error, not a warning
  SavedMapCli map;        ///< psm-slam: --load-map, --mode, --initial-pose (docs/maps.md)
};

/// The estimator of a run: the pipeline's, or PSM SLAM with its map options. Refuses options
/// that do not go together.
std::unique_ptr<Estimator> makeEstimator(const RunOptions& o) {
  if (o.pipeline == "psm-slam")
    return makePsmSlamEstimator(loadPsmSlamEstimatorConfig(o.pipeline_options.config), o.map.resolve(o.save_map));
  if (!o.save_map.empty()) throw std::runtime_error("--save-map goes with --pipeline psm-slam");
  if (!o.map.loadMap().empty()) throw std::runtime_error("--load-map goes with --pipeline psm-slam");
  if (o.map.hasInitialPose()) throw std::runtime_error("--initial-pose goes with --load-map");
  return pipelines().at(o.pipeline)(o.pipeline_options);
}

std::atomic<int> stop_signal{0};
extern "C" void requestStop(int signal_number) { stop_signal = signal_number; }

/// The run writes into OUT.incomplete and only a finished run becomes OUT (replacing an older
/// one whole), so an interrupted run never leaves a partial folder and two runs never mix files.
class OutputFolder {
 public:
  explicit OutputFolder(std::filesystem::path final_dir)
      : final_(std::move(final_dir)), work_(final_.string() + ".incomplete") {
    std::filesystem::remove_all(work_);
    std::filesystem::create_directories(work_);
  }
  ~OutputFolder() {
    std::error_code ignored;
    if (!published_) std::filesystem::remove_all(work_, ignored);
  }
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& work() const { return work_; }
  void publish() {
    const std::filesystem::path old = final_.string() + ".old";
    std::filesystem::remove_all(old);
    if (std::filesystem::exists(final_)) std::filesystem::rename(final_, old);
    std::filesystem::rename(work_, final_);
    std::filesystem::remove_all(old);
    published_ = true;
  }

 private:
  std::filesystem::path final_, work_;
  bool published_ = false;
};

/// SIGINT and SIGTERM end the run between two messages (the handlers are restored on return).
class StopOnSignals {
 public:
  StopOnSignals() {
    stop_signal = 0;
    previous_int_ = std::signal(SIGINT, requestStop);
    previous_term_ = std::signal(SIGTERM, requestStop);
  }
  ~StopOnSignals() {
    std::signal(SIGINT, previous_int_);
    std::signal(SIGTERM, previous_term_);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;
  void throwIfStopped(const std::string& out) const {
    if (const int sig = stop_signal.load(); sig != 0)
      throw std::runtime_error(std::string("stopped by ") + (sig == SIGINT ? "SIGINT" : "SIGTERM") +
                               ": nothing written to '" + out + "'");
  }

 private:
  void (*previous_int_)(int) = SIG_DFL;
  void (*previous_term_)(int) = SIG_DFL;
};

/// File names the estimators put in the report point into the work folder: name the final one.
void relocatePaths(nlohmann::json& value, const std::string& from, const std::string& to) {
  if (value.is_string()) {
    const std::string& text = value.get_ref<const std::string&>();
    if (text.starts_with(from)) value = to + text.substr(from.size());
  } else if (value.is_structured()) {
    for (auto& item : value) relocatePaths(item, from, to);
  }
}

bool usesLaser(const RunOptions& o) {
  if (o.pipeline == "psm" || o.pipeline == "psm-slam") return true;
  return o.pipeline == "ekf" && o.pipeline_options.sensors != "sonar";
}

bool hasAReturn(const LaserScan& scan) {
  for (size_t i = 0; i < scan.ranges.size(); ++i)
    if (scan.valid(i)) return true;
  return false;
}

/// A laser pipeline that never saw a usable scan has only dead reckoning to show: say so on
/// stderr and in the report, or fail with --strict.
void checkLaserData(const RunOptions& o, int64_t scans, int64_t usable_scans, nlohmann::json& report) {
  if (!usesLaser(o) || usable_scans > 0) return;
  const std::string why = scans == 0 ? "the log has no " + o.channels.laser + " message"
                                     : "none of the " + std::to_string(scans) + " " + o.channels.laser +
                                           " scans has a valid range";
  const std::string what = why + ": the " + o.pipeline + " trajectory is odometry only";
  if (o.strict) throw std::runtime_error(what + " (--strict)");
  std::cerr << "warning: run " << o.pipeline << ": " << what << "\n";
  report["warnings"].push_back(what);
}

std::vector<Vec2> positions(const std::vector<PoseStamped>& poses) {
  std::vector<Vec2> out;
  out.reserve(poses.size());
  for (const auto& p : poses) out.push_back(p.pose.translation());
  return out;
}

void plotTrajectories(const std::string& path, const std::string& title, const std::vector<PoseStamped>& estimate,
                      const std::vector<PoseStamped>& truth, const std::vector<PoseStamped>& odometry) {
  Plot plot;
  plot.title = title;
  if (!truth.empty()) plot.series.push_back({"ground truth", positions(truth), {0, 0, 0}, 2.0, 0});
  if (!odometry.empty()) plot.series.push_back({"odometry", positions(odometry), {150, 150, 150}, 1.2, 0});
  plot.series.push_back({"estimate", positions(estimate), seriesColor(0), 1.8, 0});
  writePlotPng(path, plot);
}

void plotErrorOverTime(const std::string& path, const std::vector<PoseStamped>& estimate,
                       const std::vector<PoseStamped>& truth) {
  if (estimate.empty() || truth.empty()) return;
  Plot plot;
  plot.title = "position error over time";
  plot.x_label = "time [s]";
  plot.y_label = "error [m]";
  plot.equal_axes = false;
  PlotSeries series{"|estimate - ground truth|", {}, seriesColor(1), 1.5, 0};
  size_t j = 0;
  const int64_t t0 = estimate.front().utime;
  for (const auto& e : estimate) {
    while (j + 1 < truth.size() && std::llabs(truth[j + 1].utime - e.utime) <= std::llabs(truth[j].utime - e.utime)) ++j;
    if (std::llabs(truth[j].utime - e.utime) > 100000) continue;
    series.points.push_back({static_cast<double>(e.utime - t0) * 1e-6, (e.pose.translation() - truth[j].pose.translation()).norm()});
  }
  plot.series.push_back(series);
  writePlotPng(path, plot);
}

/// The channels a recorded live run published next to its poses: EKF SLAM (SLAM_POSE) also
/// SCAN_ANCHORS and SLAM_MAP, PSM SLAM (PSM_SLAM_POSE) also PSM_SLAM_ANCHORS, PSM_SLAM_GRAPH and
/// PSM_SLAM_PATH.
void addRecordedChannels(SensorChannelNames& c) {
  if (c.estimated_pose == "SLAM_POSE") {
    if (c.scan_anchors.empty()) c.scan_anchors = "SCAN_ANCHORS";
    if (c.slam_map.empty()) c.slam_map = "SLAM_MAP";
  } else if (c.estimated_pose == "PSM_SLAM_POSE") {
    if (c.anchored_poses.empty()) c.anchored_poses = "PSM_SLAM_ANCHORS";
    if (c.pose_graph.empty()) c.pose_graph = "PSM_SLAM_GRAPH";
    if (c.final_path.empty()) c.final_path = "PSM_SLAM_PATH";
  }
}

/// ATE figures of one trajectory against ground truth, under `prefix` (e.g. "online_").
void addAte(nlohmann::json& report, const std::string& prefix, const std::vector<PoseStamped>& estimate,
            const std::vector<PoseStamped>& truth) {
  if (truth.empty() || estimate.empty()) return;
  const AteResult ate = evaluateAte(estimate, truth);
  report[prefix + "ate"] = ateJson(ate);
  report[prefix + "ate_rmse_m"] = ate.raw_translation.rmse;
  report[prefix + "max_error_m"] = ate.raw_translation.max;
}

/// A live run's processes as their last PROCESS_STATUS left them; the drops are sequence gaps.
nlohmann::json processesJson(const std::map<std::string, ProcessCounts>& processes) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, p] : processes)
    out[name] = {{"state", p.state}, {"handled", p.handled}, {"rejected", p.rejected}, {"dropped", p.dropped}};
  return out;
}

void runPipeline(RunOptions o) {
  if (o.print_config) {
    std::cout << effectiveConfigYaml(o.pipeline, o.pipeline_options);
    return;
  }
  if (o.log.empty() || o.out.empty()) throw CLI::RequiredError("--log and --out");
  const auto& factories = pipelines();
  const auto factory = factories.find(o.pipeline);
  if (factory == factories.end()) throw std::runtime_error("unknown pipeline '" + o.pipeline + "'");
  if ((o.pipeline == "recorded") != !o.channels.estimated_pose.empty())
    throw std::runtime_error("--pose-channel goes with --pipeline recorded, and only with it");
  const std::string label = o.pipeline == "recorded" ? o.channels.estimated_pose + " (recorded)"
                            : o.map.loadMap().empty() ? o.pipeline
                                                      : o.pipeline + " (" + o.map.mode() + " in " + o.map.loadMap() + ")";
  if (o.pipeline == "recorded") addRecordedChannels(o.channels);
  const std::string final_out = o.out;
  const StopOnSignals stop;
  OutputFolder folder(final_out);
  o.out = folder.work().string();
  std::unique_ptr<Estimator> estimator = makeEstimator(o);
  OdometryEstimator dead_reckoning;
  std::vector<PoseStamped> truth;

  const auto start = std::chrono::steady_clock::now();
  SensorLogVisitor visitor;
  int64_t scans = 0, usable_scans = 0;
  visitor.laser = [&](const LaserScan& s) {
    stop.throwIfStopped(final_out);
    ++scans;
    if (hasAReturn(s)) ++usable_scans;
    estimator->onLaser(s);
  };
  visitor.sonar = [&](const SonarScan& s) { estimator->onSonar(s); };
  visitor.odometry = [&](const OdometryReading& r) {
    stop.throwIfStopped(final_out);
    estimator->onOdometry(r);
    dead_reckoning.onOdometry(r);
  };
  visitor.ground_truth = [&](const PoseStamped& p) { truth.push_back(p); };
  visitor.estimated_pose = [&](const PoseStamped& p) { estimator->onPose(p); };
  visitor.scan_anchors = [&](const ScanAnchors& a) { estimator->onScanAnchors(a); };
  visitor.slam_map = [&](const FeatureMap& m) { estimator->onFeatureMap(m); };
  visitor.anchored_pose = [&](const AnchoredPose& p) { estimator->onAnchoredPose(p); };
  visitor.pose_graph = [&](const PoseGraph& g) { estimator->onPoseGraph(g); };
  visitor.final_path = [&](const std::vector<PoseStamped>& path) { estimator->onFinalPath(path); };
  const SensorLogSummary summary = visitSensorLog(o.log, o.channels, visitor, "run " + o.pipeline,
                                                  {static_cast<int64_t>(o.max_time_jump_s * 1e6), 3});
  nlohmann::json report;
  checkLaserData(o, scans, usable_scans, report);
  estimator->finish(o.out, report);
  if (report.contains("saved_map") && !report["saved_map"].value("written", true)) {
    const std::string what = "--save-map " + o.save_map + " not written: " + report["saved_map"].value("reason", "");
    std::cerr << "warning: run " << o.pipeline << ": " << what << "\n";
    report["warnings"].push_back(what);
  }
  const double run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const auto& estimate = estimator->trajectory();
  const auto& online = estimator->onlineTrajectory();
  truth = inStartFrame(std::move(truth));
  writeTumTrajectory((std::filesystem::path(o.out) / "trajectory.tum").string(), estimate);
  if (&online != &estimate)
    writeTumTrajectory((std::filesystem::path(o.out) / "trajectory-online.tum").string(), online);
  report["pipeline"] = label;
  report["sensors"] = o.pipeline_options.sensors;
  report["log"] = o.log;
  report["log_duration_s"] = summary.durationSeconds();
  report["run_time_s"] = run_seconds;
  report["realtime_factor"] = run_seconds > 0 ? summary.durationSeconds() / run_seconds : 0.0;
  report["messages"] = summary.messages;
  report["rejected"] = summary.rejected;
  if (!summary.log_warnings.empty()) report["log_warnings"] = summary.log_warnings;
  if (!summary.processes.empty()) {
    report["processes"] = processesJson(summary.processes);
    int64_t dropped = 0;
    for (const auto& [name, p] : summary.processes) dropped += p.dropped;
    report["messages_dropped"] = dropped;
  }
  report["trajectory_poses"] = estimate.size();
  // The final trajectory is the run's answer; the online one is what a live user saw at scan time.
  addAte(report, "", estimate, truth);
  addAte(report, "online_", online, truth);
  const std::filesystem::path dir(o.out);
  plotTrajectories((dir / "trajectory.png").string(), label + " trajectory", estimate, truth,
                   o.pipeline == "odometry" ? std::vector<PoseStamped>{} : dead_reckoning.trajectory());
  plotErrorOverTime((dir / "error.png").string(), estimate, truth);
  relocatePaths(report, o.out, final_out);
  writeFileAtomically((dir / "report.json").string(), report.dump(2) + "\n");
  stop.throwIfStopped(final_out);
  folder.publish();
  std::cout << "run " << o.pipeline << ": " << estimate.size() << " poses, "
            << report.value("realtime_factor", 0.0) << "x real time";
  if (report.contains("ate_rmse_m"))
    std::cout << ", ATE RMSE " << report["ate_rmse_m"].get<double>() << " m (online "
              << report["online_ate_rmse_m"].get<double>() << " m)";
  std::cout << " -> " << final_out << "\n";
}

void setupRun(CLI::App& sub) {
  auto o = std::make_shared<RunOptions>();
  std::vector<std::string> names;
  for (const auto& [name, factory] : pipelines()) names.push_back(name);
  sub.add_option("--log", o->log, "LCM log with LASER, SONAR, ODOMETRY (and GROUND_TRUTH)")->check(CLI::ExistingFile);
  sub.add_flag("--print-config", o->print_config, "print the parameters the pipeline would use (YAML) and exit");
  sub.add_option("--pipeline", o->pipeline, "estimator to run")->check(CLI::IsMember(names))->capture_default_str();
  sub.add_option("--sensors", o->pipeline_options.sensors, "features for feature SLAM")
      ->check(CLI::IsMember({"laser", "sonar", "fused"}))->capture_default_str();
  sub.add_option("--config", o->pipeline_options.config, "estimator parameters (YAML)")->check(CLI::ExistingFile);
  sub.add_option("-o,--out", o->out, "output folder");
  sub.add_option("--save-map", o->save_map,
                 "with --pipeline psm-slam: save the map (pose graph, reference scans, grid, parameters) to this "
                 "folder, replacing an older map there only once the new one is complete");
  o->map.add(sub);
  sub.add_flag("--strict", o->strict,
               "fail, instead of warning, when a laser pipeline finds no usable scan (no LASER message, or no valid range)");
  sub.add_option("--max-time-jump", o->max_time_jump_s,
                 "s: a message stamped further than this from the other channels is rejected and counted")
      ->check(CLI::PositiveNumber)->capture_default_str();
  sub.add_option("--laser-channel", o->channels.laser, "channel of the laser scans (laser_scan_t)")->capture_default_str();
  sub.add_option("--sonar-channel", o->channels.sonar, "channel of the advanced-sonar cycles (sonar_targets_t)")->capture_default_str();
  sub.add_option("--odometry-channel", o->channels.odometry, "channel of the odometry (odometry_t)")->capture_default_str();
  sub.add_option("--ground-truth-channel", o->channels.ground_truth, "channel of the ground-truth poses (pose_t)")->capture_default_str();
  sub.add_option("--pose-channel", o->channels.estimated_pose,
                 "with --pipeline recorded: the pose_t channel a live run published (e.g. SLAM_POSE)");
  sub.add_option("--anchors-channel", o->channels.scan_anchors,
                 "with --pipeline recorded: scan_anchors_t (default SCAN_ANCHORS with SLAM_POSE)");
  sub.add_option("--map-channel", o->channels.slam_map,
                 "with --pipeline recorded: slam_map_t (default SLAM_MAP with SLAM_POSE)");
  sub.add_option("--anchored-pose-channel", o->channels.anchored_poses,
                 "with --pipeline recorded: anchored_pose_t (default PSM_SLAM_ANCHORS with PSM_SLAM_POSE)");
  sub.add_option("--graph-channel", o->channels.pose_graph,
                 "with --pipeline recorded: pose_graph_t (default PSM_SLAM_GRAPH with PSM_SLAM_POSE)");
  sub.callback([o] { runPipeline(*o); });
}

RegisterCommand reg_run("run", "Run a SLAM pipeline offline over an LCM log; write trajectory, maps and a report", setupRun);

}  // namespace
}  // namespace polarslam
