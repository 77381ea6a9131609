// bench_psm_slam: PSM SLAM on a CARMEN log with Kümmerle relations (by default MIT CSAIL from
// ../shared/data), next to chained PSM laser odometry and raw odometry, scored with the relation
// metric; run time as a multiple of real time on one core (time inside the estimators only: the
// log is parsed before the clock starts). Prints a table with the goals and writes JSON.
//
//   bench_psm_slam [--log X.clf --relations R] [--out DIR] [--config psm_slam.yaml]
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>

#include "eval/relation_metric.hpp"
#include "io/carmen.hpp"
#include "io/range_log.hpp"
#include "io/relations.hpp"
#include "io/tum.hpp"
#include "scanmatch/laser_odometry.hpp"
#include "pipeline/estimator.hpp"
#include "slam/psm_slam.hpp"
#include "pipeline/psm_slam_estimator.hpp"

using namespace polarslam;

namespace {

constexpr double kCartographerTranslation = 0.0319;  ///< m, Hess et al. 2016 Table II, MIT CSAIL
constexpr double kCartographerRotation = 0.369;      ///< deg
constexpr double kRealTimeGoal = 100.0;

struct Result {
  std::string name;
  std::vector<PoseStamped> trajectory;
  double seconds = 0.0;
  nlohmann::json extra;
};

double secondsOf(const std::function<void()>& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Result runOdometry(const CarmenLog& log) {
  Result r{"raw odometry", {}, 0.0, {}};
  OdometryEstimator odometry;
  r.seconds = secondsOf([&] {
    for (const auto& e : log.events)
      if (!e.isLaser()) odometry.onOdometry(e.odometry());
  });
  r.trajectory = odometry.trajectory();
  return r;
}

Result runLaserOdometry(const CarmenLog& log) {
  Result r{"PSM laser odometry (keyframes, PSM engineer's LaserOdometry)", {}, 0.0, {}};
  LaserOdometry odometry;
  size_t rejected = 0;
  r.seconds = secondsOf([&] {
    for (const auto& e : log.events) {
      if (!e.isLaser()) {
        odometry.addOdometry(e.odometry());
      } else if (validateScan(e.laser()).empty()) {
        odometry.addScan(e.laser());
      } else {
        ++rejected;
      }
    }
  });
  r.trajectory = odometry.trajectory();
  r.extra = {{"keyframes", odometry.keyframes()}, {"failed_matches", odometry.failedMatches()},
             {"held_scans", odometry.heldScans()}, {"rejected_scans", rejected}};
  return r;
}

Result runPsmSlam(const CarmenLog& log, const PsmSlamParams& params, std::vector<PoseStamped>& online_trajectory) {
  Result r{"PSM SLAM", {}, 0.0, {}};
  PsmSlam slam(params);
  PoseGraphOptimizationSummary final_summary;
  GraphRefinementSummary refinement;
  std::vector<PoseStamped> online;
  online.reserve(static_cast<size_t>(log.laserCount()));
  r.seconds = secondsOf([&] {
    for (const auto& e : log.events)
      if (e.isLaser()) online.push_back(slam.addScan(e.laser()).pose);
      else slam.addOdometry(e.odometry());
    refinement = slam.refine();
    final_summary = slam.optimize();
  });
  online_trajectory = std::move(online);
  r.trajectory = slam.trajectory();
  r.extra = psmSlamReportJson(slam, final_summary);
  r.extra["refinement"] = refinementJson(refinement);
  return r;
}

nlohmann::json statsJson(const ErrorStatistics& s) {
  return {{"mean", s.mean}, {"std", s.std}, {"min", s.min}, {"max", s.max}, {"count", s.count}};
}

/// Relations whose two poses are less than 30 s apart (the "local" accuracy of docs/algorithms.md's appendix).
std::vector<Relation> localRelations(const std::vector<Relation>& relations) {
  std::vector<Relation> local;
  for (const auto& r : relations)
    if (std::llabs(r.t2 - r.t1) < 30'000'000) local.push_back(r);
  return local;
}

void printRow(const std::string& name, const RelationMetric& all, const RelationMetric& local, double realtime) {
  std::printf("%-28s %7.4f ± %-7.4f %6.3f ± %-6.3f %7.3f %5zu | %7.4f | %8.0fx\n", name.c_str(), all.translation.mean,
              all.translation.std, all.rotation_deg.mean, all.rotation_deg.std, all.translation.max, all.evaluated,
              local.translation.mean, realtime);
}

}  // namespace

/// The real logs without ground truth (data README): each runs through the whole psm-slam
/// pipeline, as `polarslam run --pipeline psm-slam` does, and leaves its map.png for a person to
/// judge. Laser mounts as the README gives them (the readers' defaults, Málaga's 0.78 m here).
struct OtherLog {
  std::string name, path;
  Pose2 carmen_mount;
};

std::vector<OtherLog> otherLogs(const std::string& data) {
  return {{"malaga-2006", data + "/malaga-2006/malaga-one-loop.clf", {0.78, 0.0, 0.0}},
          {"cmu-wean-hall-1", data + "/cmu-wean-hall/robotdata1.log.gz", {}},
          {"cmu-wean-hall-2", data + "/cmu-wean-hall/robotdata2.log.gz", {}},
          {"duke-loop5", data + "/duke-loop5/loop5.log", {}},
          {"mines-paristech-1", data + "/mines-paristech/exp1.dat", {}},
          {"mines-paristech-2", data + "/mines-paristech/exp2.dat", {}}};
}

/// Runs every log found; returns false when any failed (a throw or no map written).
bool runOtherLogs(const std::string& data, const std::string& out, const PsmSlamEstimatorConfig& config,
                  nlohmann::json& report) {
  std::printf("\nOther real logs (no ground truth): PSM SLAM end to end, maps in %s/<log>/map.png\n", out.c_str());
  std::printf("%-18s %6s %7s %8s %9s %5s %5s %6s %7s  %s\n", "log", "scans", "data s", "slam s", "realtime", "keyf",
              "loops", "fails", "malf.", "map");
  bool ok = true;
  for (const OtherLog& other : otherLogs(data)) {
    if (!std::filesystem::exists(other.path)) {
      std::printf("%-18s SKIPPED: %s not found\n", other.name.c_str(), other.path.c_str());
      continue;
    }
    try {
      RangeLogOptions options;
      options.carmen.flaser_laser_pose = other.carmen_mount;
      const RangeLog log = readRangeLogFile(other.path, RangeLogFormat::Auto, options);
      PsmSlamEstimator estimator(config);
      for (const auto& e : log.events) {
        if (!e.isLaser()) estimator.onOdometry(e.odometry());
        else if (validateScan(e.laser()).empty()) estimator.onLaser(e.laser());
      }
      const std::string dir = (std::filesystem::path(out) / other.name).string();
      nlohmann::json run;
      estimator.finish(dir, run);
      const auto& trajectory = estimator.trajectory();
      const double duration =
          trajectory.size() > 1 ? 1e-6 * static_cast<double>(trajectory.back().utime - trajectory.front().utime) : 0.0;
      const bool written = run["grid"].value("written", false);
      ok = ok && written;
      const auto& s = run["psm_slam"];
      std::printf("%-18s %6lld %7.1f %8.2f %8.0fx %5d %5d %6d %7lld  %s\n", other.name.c_str(),
                  static_cast<long long>(log.laserCount()), duration, estimator.slamSeconds(),
                  estimator.slamSeconds() > 0 ? duration / estimator.slamSeconds() : 0.0, s["keyframes"].get<int>(),
                  s["loop_closures"].get<int>(), s["match_failures"].get<int>(),
                  static_cast<long long>(log.malformed_count), written ? (dir + "/map.png").c_str() : "NOT WRITTEN");
      run["log"] = other.path;
      run["malformed_lines"] = log.malformed_count;
      report["other_logs"][other.name] = run;
    } catch (const std::exception& e) {
      ok = false;
      std::printf("%-18s FAILED: %s\n", other.name.c_str(), e.what());
      report["other_logs"][other.name] = {{"error", e.what()}};
    }
  }
  return ok;
}

/// The relations' own error where they can be checked against each other (relationConsistency),
/// next to PSM SLAM's error on those relations and on the others: a floor no estimate gets under.
void printRelationFloor(const std::vector<Relation>& relations, const RelationMetric& slam, nlohmann::json& report) {
  const RelationConsistency consistency = relationConsistency(relations);
  std::vector<bool> in_triangle(relations.size(), false);
  for (const size_t i : consistency.relations) in_triangle[i] = true;
  double in_sum = 0.0, out_sum = 0.0;
  size_t in_count = 0, out_count = 0;
  for (const RelationError& e : slam.errors) {
    (in_triangle[e.relation_index] ? in_sum : out_sum) += e.translation;
    (in_triangle[e.relation_index] ? in_count : out_count) += 1;
  }
  const double in_mean = in_count ? in_sum / static_cast<double>(in_count) : 0.0;
  const double out_mean = out_count ? out_sum / static_cast<double>(out_count) : 0.0;
  std::printf("the relations' own error: %zu triangles of relations (a-b, b-c, a-c) disagree by %.4f m, %.3f deg "
              "(mean), about %.4f m per relation;\n  PSM SLAM's error on the %zu relations in them %.4f m, on the "
              "other %zu %.4f m\n",
              consistency.triangles, consistency.translation.mean, consistency.rotation_deg.mean,
              consistency.per_relation_translation, in_count, in_mean, out_count, out_mean);
  report["relation_consistency"] = {{"triangles", consistency.triangles},
                                    {"relations_in_triangles", consistency.relations.size()},
                                    {"triangle_translation_m", statsJson(consistency.translation)},
                                    {"triangle_rotation_deg", statsJson(consistency.rotation_deg)},
                                    {"per_relation_translation_m", consistency.per_relation_translation},
                                    {"psm_slam_error_in_triangles_m", in_mean},
                                    {"psm_slam_error_elsewhere_m", out_mean}};
}

/// MIT CSAIL with its relations: raw odometry, PSM laser odometry and PSM SLAM side by side.
void runMitCsail(const std::string& log_path, const std::string& relations_path, const std::string& out,
                 const std::string& config, nlohmann::json& report) {
  const CarmenLog log = readCarmenLogFile(log_path);
  const std::vector<Relation> relations = readRelations(relations_path), local = localRelations(relations);
  int64_t first = 0, last = 0;
  bool any = false;
  for (const auto& e : log.events) {
    if (!e.isLaser()) continue;
    first = any ? std::min(first, e.utime()) : e.utime();
    last = any ? std::max(last, e.utime()) : e.utime();
    any = true;
  }
  const double duration = 1e-6 * static_cast<double>(last - first);
  const PsmSlamParams params = loadPsmSlamEstimatorConfig(config).slam;

  std::vector<PoseStamped> online;
  std::vector<Result> results{runOdometry(log), runLaserOdometry(log), runPsmSlam(log, params, online)};
  std::printf("\n%s: %lld scans, %.1f s of data, %zu relations (%zu within 30 s)\n", log_path.c_str(),
              static_cast<long long>(log.laserCount()), duration, relations.size(), local.size());
  std::printf("%-28s %-17s %-15s %7s %5s | %7s | %9s\n", "estimator", "trans. err [m]", "rot. err [deg]", "max [m]",
              "n", "local", "realtime");
  report["log"] = log_path;
  report["relations"] = relations_path;
  report["log_duration_s"] = duration;
  report["goals"] = {{"translation_m_below", kCartographerTranslation}, {"realtime_factor_at_least", kRealTimeGoal}};
  for (const Result& r : results) {
    const RelationMetric all = evaluateRelations(r.trajectory, relations);
    const RelationMetric near = evaluateRelations(r.trajectory, local);
    const double realtime = r.seconds > 0 ? duration / r.seconds : 0.0;
    printRow(r.name.substr(0, 28), all, near, realtime);
    nlohmann::json entry{{"name", r.name},
                         {"seconds", r.seconds},
                         {"realtime_factor", realtime},
                         {"translation_m", statsJson(all.translation)},
                         {"rotation_deg", statsJson(all.rotation_deg)},
                         {"local_translation_m", statsJson(near.translation)},
                         {"local_rotation_deg", statsJson(near.rotation_deg)},
                         {"evaluated", all.evaluated},
                         {"details", r.extra}};
    report["estimators"].push_back(entry);
    if (!out.empty()) {
      std::filesystem::create_directories(out);
      std::string file = r.name.substr(0, r.name.find(' ', 4));
      for (char& c : file) c = c == ' ' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      writeTumTrajectory((std::filesystem::path(out) / (file + ".tum")).string(), r.trajectory);
    }
  }
  const Result& slam = results.back();
  const RelationMetric slam_metric = evaluateRelations(slam.trajectory, relations);
  const double slam_realtime = duration / slam.seconds;
  std::printf("%-28s %7.4f ± %-7.4f %6.3f ± %-6.3f\n", "Cartographer (published)", kCartographerTranslation, 0.0363,
              kCartographerRotation, 0.365);
  std::printf("goal: translational error < %.4f m: %s (%.4f m); >= %.0fx real time on one core: %s (%.0fx)\n",
              kCartographerTranslation, slam_metric.translation.mean < kCartographerTranslation ? "MET" : "NOT MET",
              slam_metric.translation.mean, kRealTimeGoal, slam_realtime >= kRealTimeGoal ? "MET" : "NOT MET",
              slam_realtime);
  std::cout << "PSM SLAM details: " << slam.extra.dump() << "\n";
  const RelationMetric online_metric = evaluateRelations(online, relations);
  std::printf("PSM SLAM as published online (filter pose at each scan, before later corrections): %.4f ± %.4f m, "
              "%.3f ± %.3f deg\n", online_metric.translation.mean, online_metric.translation.std,
              online_metric.rotation_deg.mean, online_metric.rotation_deg.std);
  report["psm_slam_online"] = {{"translation_m", statsJson(online_metric.translation)},
                               {"rotation_deg", statsJson(online_metric.rotation_deg)}};
  printRelationFloor(relations, slam_metric, report);
  if (!out.empty()) writeTumTrajectory((std::filesystem::path(out) / "psm-slam-online.tum").string(), online);
}

int main(int argc, char** argv) {
  CLI::App app{"bench_psm_slam: PSM SLAM vs PSM laser odometry vs raw odometry, relation metric and speed"};
  const std::string data = POLARSLAM_SHARED_DATA_DIR;
  std::string log_path = data + "/mit-csail/mit-csail.clf", relations_path = data + "/mit-csail/mit-csail.relations";
  std::string out = "out/bench-psm-slam", config;
  bool other_logs = true;
  int status = 0;
  app.add_option("--log", log_path, "CARMEN log")->capture_default_str();
  app.add_option("--relations", relations_path, "Kümmerle relations of that log")->capture_default_str();
  app.add_option("--out", out, "folder for bench.json, the trajectories (TUM) and the other logs' maps")
      ->capture_default_str();
  app.add_flag("!--no-other-logs", other_logs, "only the log with relations");
  app.add_option("--config", config, "PSM SLAM parameters (YAML)")->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);

  nlohmann::json report;
  try {
    if (std::filesystem::exists(log_path) && std::filesystem::exists(relations_path))
      runMitCsail(log_path, relations_path, out, config, report);
    else
      std::cout << "SKIPPED: " << log_path << " or " << relations_path
                << " not found (the public logs live in ../shared/data next to the project)\n";
    const PsmSlamEstimatorConfig map_config =
        config.empty() ? PsmSlamEstimatorConfig{} : loadPsmSlamEstimatorConfig(config);
    if (other_logs && !runOtherLogs(data, out, map_config, report)) status = 1;
    std::filesystem::create_directories(out);
    std::ofstream((std::filesystem::path(out) / "bench.json").string()) << report.dump(2) << "\n";
    std::cout << "wrote " << out << "/bench.json\n";
  } catch (const std::exception& e) {
    std::cerr << "bench_psm_slam: " << e.what() << "\n";
    return 1;
  }
  return status;
}
