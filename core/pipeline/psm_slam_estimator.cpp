#include "pipeline/psm_slam_estimator.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "grid/grid_files.hpp"
#include "pipeline/g2o_export.hpp"
#include "io/stopwatch.hpp"

namespace polarslam {
namespace {

nlohmann::json optimizationJson(const PoseGraphOptimizationSummary& s) {
  return {{"solved", s.solved},           {"iterations", s.iterations},     {"rounds", s.rounds},
          {"initial_cost", s.initial_cost}, {"final_cost", s.final_cost},   {"seconds", s.seconds},
          {"rejected_loops", s.rejected_loops}, {"nodes", s.nodes},        {"edges", s.edges},
          {"message", s.message}};
}

}  // namespace

void describePsmSlamEstimatorConfig(ParameterTable& table, PsmSlamEstimatorConfig& c) {
  describePsmSlamParams(table, c.slam);
  ParameterTable& grid = table.section("grid", "the occupancy grid of the map");
  grid.number("resolution", c.map.resolution, 0.005, 5.0, "m per cell");
  grid.number("max_range", c.map.max_range, 0.0, 1000.0, "m: longer beams only clear space (0 = the laser's)");
  grid.choice(
      "scans", {"keyframes", "all"},
      [&c](const std::string& w) {
        c.map.all_scans = w == "all";
        return true;
      },
      [&c] { return std::string(c.map.all_scans ? "all" : "keyframes"); }, "the reference scans, or every scan");
  ParameterTable& sonar = table.section("sonar", "advanced-sonar planes in the laser scans (where the robot has sonar)");
  sonar.boolean("fill_planes", c.sonar.fill_planes, "walls the sonar sees fill the laser beams that pass them (glass)");
  sonar.number("half_extent", c.sonar.fill.half_extent, 0.0, 100.0, "m along a wall either side of the echo");
  sonar.number("margin", c.sonar.fill.margin, 0.0, 10.0, "m: a laser reading this far beyond the wall is behind it");
  sonar.number("max_age", c.sonar.max_age, 0.0, 10.0, "s: older sonar scans are not used");
  sonar.number("repeat_distance", c.sonar.fill.repeat_distance, 0.0, 10.0,
               "m: a plane the previous sonar scan also saw lies this close to its line");
  sonar.angle("repeat_angle_deg", c.sonar.fill.repeat_angle, 0.0, 180.0, "... and turned at most this much");
  sonar.number("laser_seen_fraction", c.sonar.fill.laser_seen_fraction, 0.0, 1.0,
               "a wall the laser sees along more of its beams is no glass: not filled");
  sonar.number("max_return_fraction", c.sonar.fill.max_return_fraction, 0.0, 1.0,
               "only a scan with laser returns on fewer of its beams is filled");
}

PsmSlamEstimatorConfig loadPsmSlamEstimatorConfig(const std::string& yaml_path) {
  PsmSlamEstimatorConfig config;
  if (yaml_path.empty()) return config;
  const YamlFields yaml(yaml_path);
  ParameterTable table;
  describePsmSlamEstimatorConfig(table, config);
  table.read(yaml, yaml.root(), "psm-slam");
  return config;
}

GridOptions gridOptions(const PsmSlamMapOptions& map) {
  GridOptions options;
  options.resolution = map.resolution;
  options.max_range = map.max_range;
  return options;
}

PsmSlamEstimator::PsmSlamEstimator(PsmSlamEstimatorConfig config)
    : config_(std::move(config)), slam_(config_.slam), map_scans_(config_.map.all_scans) {}

void PsmSlamEstimator::onOdometry(const OdometryReading& odometry) {
  odometry_pose_ = odometry.pose;
  const auto start = std::chrono::steady_clock::now();
  slam_.addOdometry(odometry);
  slam_seconds_ += secondsSince(start);
}

void PsmSlamEstimator::onSonar(const SonarScan& scan) {
  if (!config_.sonar.fill_planes) return;
  SonarPlanesSeen seen{scan.utime, odometry_pose_, sonarPlanes(scan), {}};
  if (const auto previous = sonar_planes_.find(scan.sensor_id); previous != sonar_planes_.end()) {
    const Pose2 motion = between(previous->second.odometry, odometry_pose_);
    std::vector<SonarPlane> before;
    for (const SonarPlane& p : previous->second.planes) before.push_back(movedPlane(p, motion));
    seen.repeated = repeatedPlanes(seen.planes, before, config_.sonar.fill);
  }
  sonar_planes_[scan.sensor_id] = std::move(seen);
}

void PsmSlamEstimator::onLaser(const LaserScan& laser) {
  LaserScan scan = laser;
  std::vector<SonarPlane> planes;
  for (const auto& [sensor, seen] : sonar_planes_) {
    if (std::abs(1e-6 * static_cast<double>(scan.utime - seen.utime)) > config_.sonar.max_age) continue;
    const Pose2 motion = between(seen.odometry, odometry_pose_);  // robot now, in the robot frame of the sonar scan
    for (const SonarPlane& p : seen.repeated) planes.push_back(movedPlane(p, motion));
  }
  if (!planes.empty() && laserSeesLittle(scan, config_.slam.psm.max_range, config_.sonar.fill))
    sonar_filled_readings_ += fillFromSonarPlanes(scan, planes, config_.sonar.fill);
  const auto start = std::chrono::steady_clock::now();
  last_result_ = slam_.addScan(scan);
  slam_seconds_ += secondsSince(start);
  online_.push_back(last_result_.pose);
  anchors_.push_back(last_result_.anchor);
  map_scans_.add(scan, last_result_.anchor);
}

void PsmSlamEstimator::localizeIn(const StoredMap& map, const Pose2& start, const Mat3& start_cov) {
  continueMap(map, start, start_cov);
  slam_.freezeMap();
}

void PsmSlamEstimator::continueMap(const StoredMap& map, const Pose2& start, const Mat3& start_cov,
                                   const std::optional<PsmSlamFilterSeed>& seed) {
  std::vector<LaserScan> references(map.graph.nodes().size());
  std::vector<bool> found(references.size(), false);
  for (const MapReferenceScan& s : map.scans) {
    const long index = map.graph.indexOf(s.anchor.node);
    if (index < 0 || found[static_cast<size_t>(index)]) continue;
    references[static_cast<size_t>(index)] = s.scan;
    found[static_cast<size_t>(index)] = true;
  }
  const auto missing = std::find(found.begin(), found.end(), false);
  if (missing != found.end())
    throw std::invalid_argument("the map has no reference scan for graph node " +
                                std::to_string(map.graph.nodes()[static_cast<size_t>(missing - found.begin())].id) +
                                ": it cannot be continued");
  slam_.continueMap(map.graph, references, start, start_cov, seed, map.node_covariances);
  for (const MapReferenceScan& s : map.scans) map_scans_.addStored(s.scan, s.anchor);
}

nlohmann::json refinementJson(const GraphRefinementSummary& r) {
  return {{"pairs", r.pairs},   {"edges", r.edges},     {"poor", r.poor}, {"disagreed", r.disagreed},
          {"seconds", r.seconds}, {"background_rounds", r.background_rounds}, {"final_seconds", r.final_seconds}};
}

nlohmann::json psmSlamReportJson(const PsmSlam& slam, const PoseGraphOptimizationSummary& final_optimization) {
  const PsmSlamStats& s = slam.stats();
  const PoseGraph& g = slam.graph();
  size_t inactive = 0;
  for (const auto& e : g.edges()) inactive += e.active ? 0 : 1;
  return {{"scans", s.scans},
          {"unusable_scans", s.unusable_scans},
          {"tracked_scans", s.tracked_scans},
          {"held_scans", s.held_scans},
          {"match_failures", s.match_failures},
          {"gate_rejections", s.gate_rejections},
          {"keyframes", s.keyframes},
          {"filter_keyframes", slam.filter().keyframeCount()},
          {"reference_reuses", s.reference_reuses},
          {"new_reference_reasons",
           {{"lost", s.references_lost}, {"too_far", s.references_too_far}, {"turned", s.references_turned},
            {"overlap", s.references_overlap}}},
          {"candidate_matches", s.candidate_matches},
          {"loop_closures", s.loop_closures},
          {"map_candidate_matches", s.map_candidate_matches}, {"map_loop_closures", s.map_loop_closures},
          {"loop_failed_matches", s.loop_failed_matches}, {"loop_poor_matches", s.loop_poor_matches}, {"loop_ambiguous", s.loop_ambiguous}, {"loop_gate_rejections", s.loop_gate_rejections}, {"loop_unconfirmed", s.loop_unconfirmed}, {"loop_refuted", s.loop_refuted}, {"loop_unverified", s.loop_unverified}, {"loop_unfiltered_refuted", s.loop_unfiltered_refuted},
          {"optimizations", s.optimizations},
          {"optimization_seconds", s.optimization_seconds},
          {"rejected_loop_edges", s.rejected_loop_edges},
          {"odometry_rejected", s.odometry_rejected}, {"odometry_faults", s.odometry_faults},
          {"filter_flushes", s.filter_flushes},
          {"graph",
           {{"nodes", g.nodes().size()},
            {"odometry_edges", g.countEdges(PoseGraphEdgeKind::Odometry)},
            {"match_edges", g.countEdges(PoseGraphEdgeKind::Match)},
            {"loop_edges", g.countEdges(PoseGraphEdgeKind::Loop)},
            {"refinement_edges", g.countEdges(PoseGraphEdgeKind::Refinement)},
            {"inactive_edges", inactive}}},
          {"final_optimization", optimizationJson(final_optimization)}};
}

void PsmSlamEstimator::finish(const std::string& out_dir, nlohmann::json& report) {
  const auto start = std::chrono::steady_clock::now();
  refinement_ = slam_.refine();
  const PoseGraphOptimizationSummary summary = slam_.optimize();
  final_ = reanchor(anchors_, slam_.graph());
  finished_ = true;
  slam_seconds_ += secondsSince(start);
  nlohmann::json section = psmSlamReportJson(slam_, summary);
  section["slam_seconds"] = slam_seconds_;
  section["refinement"] = refinementJson(refinement_);
  section["sonar_filled_readings"] = sonar_filled_readings_;
  report["psm_slam"] = section;
  if (out_dir.empty()) {
    if (!save_map_dir_.empty()) saveWithGrid(report);
    return;
  }
  writeMap(out_dir, report);
  writeG2o((std::filesystem::path(out_dir) / "graph.g2o").string(), slam_.graph());
}

void PsmSlamEstimator::writeMap(const std::string& out_dir, nlohmann::json& report) {
  if (map_scans_.size() == 0) {
    report["grid"] = {{"written", false}, {"reason", "no usable scans"}};
    if (!save_map_dir_.empty()) saveStoredMap(nullptr, report);
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  const GridOptions options = gridOptions(config_.map);
  const GraphGrid grid = buildGraphGrid(map_scans_, slam_.graph(), options);
  GridPicture picture = graphGridPicture(grid, slam_.graph(), final_);
  picture.title = "psm-slam: occupancy grid of the reference scans";
  const GridSlice& slice = grid.slice;
  const GridFiles files = writeGridFiles(out_dir, grid.grid, slice, picture);
  report["grid"] = {{"written", true},
                    {"scans", map_scans_.size()},
                    {"resolution_m", options.resolution},
                    {"max_range_m", options.max_range},
                    {"width", slice.width},
                    {"height", slice.height},
                    {"build_seconds", grid.build_seconds},
                    {"files", {files.ot, files.bt, files.pgm, files.yaml, files.png}},
                    {"seconds", secondsSince(start)}};
  if (!save_map_dir_.empty()) saveStoredMap(&grid.grid, report);
}

StoredMap PsmSlamEstimator::storedMap() const {
  PsmSlamEstimatorConfig config = config_;
  ParameterTable table;
  describePsmSlamEstimatorConfig(table, config);
  StoredMap map = storedMapOf(slam_.graph(), map_scans_.scans(), map_scans_.anchors(), table.yaml());
  map.node_covariances = slam_.nodeCovariances();
  return map;
}

void PsmSlamEstimator::saveMapNow() const {
  nlohmann::json ignored;
  saveWithGrid(ignored);
}

void PsmSlamEstimator::saveWithGrid(nlohmann::json& report) const {
  if (map_scans_.size() == 0) return saveStoredMap(nullptr, report);
  const GraphGrid grid = buildGraphGrid(map_scans_, slam_.graph(), gridOptions(config_.map));
  saveStoredMap(&grid.grid, report);
}

void PsmSlamEstimator::saveStoredMap(const OccupancyGrid* grid, nlohmann::json& report) const {
  const auto start = std::chrono::steady_clock::now();
  const StoredMap map = storedMap();
  saveMap(save_map_dir_, map, grid);
  report["saved_map"] = {{"folder", save_map_dir_},
                         {"nodes", map.graph.nodes().size()},
                         {"edges", map.graph.edges().size()},
                         {"reference_scans", map.scans.size()},
                         {"seconds", secondsSince(start)}};
}

}  // namespace polarslam
