// bench_localize: issue 15's localisation goals on MIT CSAIL (../shared/data, or --log/--relations):
// PSM SLAM maps the first half of the log; the second half is localised in that map with its
// odometry moved far away by a rigid transform (core/pipeline/map_then_localize.hpp). Prints when
// the start was found (goal: within 10 scans), the relation error of the joined trajectory next to
// full-run SLAM's (goal: ≤ 1.25×, relations across the halves included) and the localisation
// speed (goal: ≥ 500× real time), with the localiser's counts.
//
//   bench_localize [--log X.clf --relations R] [--config psm-slam.yaml]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "eval/relation_metric.hpp"
#include "io/relations.hpp"
#include "pipeline/map_then_localize.hpp"

using namespace polarslam;

int main(int argc, char** argv) {
  CLI::App app{"bench_localize: map the first half of a log, localise the second half in that map"};
  const std::string data = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail/";
  std::string log_path = data + "mit-csail.clf", relations_path = data + "mit-csail.relations";
  std::string config_path = std::string(POLARSLAM_SOURCE_DIR) + "/config/psm-slam.yaml";
  app.add_option("--log", log_path, "CARMEN log")->capture_default_str();
  app.add_option("--relations", relations_path, "Kümmerle relations of the log")->capture_default_str();
  app.add_option("--config", config_path, "PSM SLAM parameters")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (!std::filesystem::exists(log_path)) {
    std::printf("bench_localize: %s is absent; nothing to measure\n", log_path.c_str());
    return 0;
  }
  const CarmenLog log = readCarmenLogFile(log_path);
  const std::vector<Relation> relations = readRelations(relations_path);
  std::vector<int64_t> stamps;
  for (const CarmenEvent& e : log.events)
    if (e.isLaser()) stamps.push_back(e.utime());
  std::sort(stamps.begin(), stamps.end());
  const int64_t split = stamps[stamps.size() / 2];
  const PsmSlamEstimatorConfig config = loadPsmSlamEstimatorConfig(config_path);

  PsmSlamEstimator full_run(config);
  for (const CarmenEvent& e : log.events) {
    if (e.isLaser()) full_run.onLaser(e.laser());
    else full_run.onOdometry(e.odometry());
  }
  nlohmann::json report;
  full_run.finish("", report);
  const RelationMetric full = evaluateRelations(full_run.trajectory(), relations);

  const MapThenLocalizeResult result = mapThenLocalize(log.events, split, Pose2(250.0, -120.0, 2.0), config);
  const RelationMetric joined = evaluateRelations(result.joined, relations);
  size_t across = 0;
  for (const Relation& r : relations)
    if ((r.t1 < split) != (r.t2 < split)) ++across;
  const MapLocalizerStats& s = result.stats;
  std::printf("%s: first half mapped (%zu reference scans), second half localised (%zu scans)\n", log_path.c_str(),
              result.reference_scans, s.scans);
  std::printf("%-44s %10s %10s\n", "figure", "measured", "goal");
  std::printf("%-44s %10lld %10s\n", "first fix, scans into the second half", static_cast<long long>(s.first_fix_scan),
              "< 10");
  std::printf("%-44s %10.4f %10s\n", "relation error, full-run SLAM [m]", full.translation.mean, "");
  std::printf("%-44s %10.4f %10s\n", "relation error, mapped + localised [m]", joined.translation.mean, "");
  std::printf("%-44s %10.2f %10s\n", "ratio", joined.translation.mean / full.translation.mean, "<= 1.25");
  std::printf("%-44s %10zu %10s\n", "relations across the split (scored)", across, "");
  std::printf("%-44s %9.0fx %10s\n", "localisation speed (real time)", result.localized_duration_s / result.localize_seconds,
              ">= 500x");
  std::printf("counts: %zu matched, %zu odometry-only, %zu match failures, %zu gate rejections, %zu global searches "
              "(%zu matches, %zu ambiguous, %zu unconfirmed), %zu fixes, %zu losses\n",
              s.matched_scans, s.odometry_only_scans, s.match_failures, s.gate_rejections, s.global_searches,
              s.global_matches, s.global_ambiguous, s.global_unconfirmed, s.fixes, s.losses);
  return 0;
}
