// polarslam map-check M [--log L]: loads a saved map (docs/maps.md) with every check loadMap
// makes (versions, sizes, CRC32s, records) and prints what it holds; with --log, also refuses a
// map made with another laser than the log's first scan; a crash-recovery snapshot is also read
// back as a restart reads it, and any other map is made ready for localisation as `run --load-map`
// makes it (a map too wide for the search's grids is refused). Exit 1 with the offending file named.
#include <chrono>
#include <iostream>
#include <optional>

#include "command_registry.hpp"
#include "map/map_store.hpp"
#include "offline_log.hpp"
#include "pipeline/psm_slam_estimator.hpp"
#include "pipeline/psm_slam_session.hpp"
#include "slam/psm_slam_filter.hpp"

namespace polarslam {
namespace {

struct MapCheckOptions {
  std::string map, log, config;
  SensorChannelNames channels;
};

std::optional<LaserGeometry> firstLaserOf(const MapCheckOptions& o) {
  if (o.log.empty()) return std::nullopt;
  std::optional<LaserGeometry> laser;
  SensorLogVisitor visitor;
  visitor.laser = [&](const LaserScan& scan) {
    if (!laser) laser = laserGeometryOf(scan);
  };
  visitSensorLog(o.log, o.channels, visitor, "map-check");
  if (!laser) throw std::runtime_error("'" + o.log + "' holds no laser scans on " + o.channels.laser);
  return laser;
}

/// What a crash-recovery snapshot (a map with resume.json) would resume: read back as
/// polarslam-psm-slam reads it, its filter state checked as a restart restores it.
void describeSnapshot(const StoredMap& map, const std::string& dir) {
  const SessionSnapshot snapshot = sessionSnapshotOf(map, dir, {});
  std::cout << "crash-recovery snapshot: mode " << snapshot.options.mode;
  if (const auto& seed = snapshot.options.filter_seed) {
    try {
      PsmSlamFilter().restore(seed->filter);
    } catch (const std::invalid_argument& e) {
      throw MapFormatError(dir + "/resume-filter.bin", "'" + dir + "/resume-filter.bin': " + e.what());
    }
    std::cout << ", a filter of " << seed->filter.ids.size() << " reference scans (" << seed->skeleton.size()
              << " of them kept for loop closure), active " << seed->filter.active;
  }
  if (snapshot.options.initial_pose) {
    const Pose2& p = *snapshot.options.initial_pose;
    std::cout << ", robot at " << p.x << ", " << p.y << ", " << p.theta;
  }
  std::cout << "; resumable\n";
}

/// Builds what localising in the map or continuing it builds (the global search's grids), with
/// the parameters of o.config: a map spreading wider than those grids allow is refused here, as
/// `run --load-map` would refuse it, naming the map and its span.
void checkLocalisable(std::shared_ptr<const StoredMap> map, const MapCheckOptions& o) {
  SavedMapOptions saved;
  saved.load_map = o.map;
  saved.loaded_map = std::move(map);
  const auto start = std::chrono::steady_clock::now();
  makePsmSlamEstimator(loadPsmSlamEstimatorConfig(o.config), saved);
  std::cout << "localisable: the global search's grids built in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s\n";
}

void checkMap(const MapCheckOptions& o) {
  const std::optional<LaserGeometry> laser = firstLaserOf(o);
  const auto start = std::chrono::steady_clock::now();
  auto loaded = std::make_shared<const StoredMap>(loadMap(o.map, laser));
  const StoredMap& map = *loaded;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "map " << o.map << ": format " << kMapFormatName << " version " << kMapFormatVersion << ", "
            << map.graph.nodes().size() << " nodes, " << map.graph.edges().size() << " edges ("
            << map.graph.countEdges(PoseGraphEdgeKind::Loop) << " active loop closures), " << map.scans.size()
            << " reference scans of " << map.laser.beams << " beams; loaded and checked in " << seconds << " s"
            << (laser ? ", laser matches the log" : "") << "\n";
  if (!map.resume_json.empty()) describeSnapshot(map, o.map);
  else checkLocalisable(std::move(loaded), o);  // a snapshot resumes its own filter instead
}

void setupMapCheck(CLI::App& sub) {
  auto o = std::make_shared<MapCheckOptions>();
  sub.add_option("map", o->map, "map folder (written by --save-map)")->required();
  sub.add_option("--log", o->log, "LCM log whose laser the map must fit")->check(CLI::ExistingFile);
  sub.add_option("--laser-channel", o->channels.laser, "channel of the laser scans (laser_scan_t)")
      ->capture_default_str();
  sub.add_option("--config", o->config, "PSM SLAM parameters localising in the map would use (YAML; default: built in)")
      ->check(CLI::ExistingFile);
  sub.callback([o] { checkMap(*o); });
}

RegisterCommand reg_map_check("map-check", "Load and check a saved map (checksums, version, laser) and summarise it",
                    setupMapCheck);

}  // namespace
}  // namespace polarslam
