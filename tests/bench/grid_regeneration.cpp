// bench_grid_regeneration: is an occupancy grid cheap enough to rebuild live after every loop
// closure? Goal: re-placing 2000 laser scans (the size of the MIT CSAIL log) and rebuilding the
// grid, i.e. buildGrid + slice(), in < 200 ms in Release on one core.
// Scans and poses: ../shared/data/mit-csail/mit-csail.clf with its odometry (fine for timing) when
// present, else scans simulated in config/worlds/office.yaml (true poses). For comparison,
// OctoMap's OcTree::insertPointCloud, which the grid used before, on every n-th of the same scans:
// time per scan and how far its cells agree with the raster's.
#include <CLI/CLI.hpp>
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "grid/occupancy_grid.hpp"
#include "io/carmen.hpp"
#include "sim/simulator.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string clf = std::string(POLARSLAM_SHARED_DATA_DIR) + "/mit-csail/mit-csail.clf";
  std::string world = std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/office.yaml";
  std::string robot = std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml";
  bool simulate = false;
  size_t scans = 2000;
  int repetitions = 7;
  size_t octomap_scans = 200;
  GridOptions grid;
};

struct ScansWithPoses {
  std::string source;
  std::vector<LaserScan> scans;
  std::vector<Pose2> poses;
};

std::optional<ScansWithPoses> fromCarmen(const Options& o) {
  if (o.simulate || !std::filesystem::exists(o.clf)) return std::nullopt;
  const CarmenLog log = readCarmenLogFile(o.clf);
  ScansWithPoses out;
  out.source = o.clf + " (odometry poses)";
  std::optional<Pose2> odometry;
  for (const CarmenEvent& e : log.events) {
    if (out.scans.size() == o.scans) break;
    if (!e.isLaser()) {
      odometry = e.odometry().pose;
    } else if (odometry) {
      out.scans.push_back(e.laser());
      out.poses.push_back(*odometry);
    }
  }
  return out;
}

/// Laser scans and the true base pose at each, from the simulator.
class ScanRecorder : public SimSink {
 public:
  ScanRecorder(const Simulator& sim, ScansWithPoses& out) : sim_(sim), out_(out) {}
  void onLaser(const LaserScan& scan) override {
    out_.scans.push_back(scan);
    out_.poses.push_back(sim_.truePose());
  }
  void onSonar(const SonarScan&) override {}
  void onOdometry(const OdometryReading&) override {}
  void onGroundTruth(const PoseStamped&) override {}

 private:
  const Simulator& sim_;
  ScansWithPoses& out_;
};

/// The office path ends after about 1500 scans: further runs of it (other seeds) until there
/// are enough, all in the world frame.
ScansWithPoses simulated(const Options& o) {
  ScansWithPoses out;
  out.source = o.world + " (simulated, true poses)";
  const World world = loadWorld(o.world);
  const RobotDescription robot = loadRobotDescription(o.robot);
  for (uint64_t seed = 1; out.scans.size() < o.scans; ++seed) {
    const size_t before = out.scans.size();
    Simulator sim(world, robot, seed);
    ScanRecorder recorder(sim, out);
    while (out.scans.size() < o.scans && !sim.finished() && sim.time() < 3600.0) sim.step(recorder);
    if (out.scans.size() == before) break;  // a world without laser scans
  }
  return out;
}

double millisecondsSince(Clock::time_point start) {
  return 1e3 * std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

size_t validBeams(const std::vector<LaserScan>& scans) {
  size_t n = 0;
  for (const LaserScan& s : scans)
    for (size_t i = 0; i < s.size(); ++i) n += s.valid(i);
  return n;
}

struct RegenerationTiming {
  double total_ms = 0.0, build_ms = 0.0, slice_ms = 0.0;
  GridSlice slice;
};

RegenerationTiming timeRegeneration(const ScansWithPoses& data, const Options& o) {
  std::vector<double> totals, builds, slices;
  RegenerationTiming r;
  for (int k = 0; k < o.repetitions; ++k) {
    const auto start = Clock::now();
    const OccupancyGrid grid = buildGrid(data.scans, data.poses, o.grid);
    const double build = millisecondsSince(start);
    const auto slice_start = Clock::now();
    r.slice = grid.slice();
    slices.push_back(millisecondsSince(slice_start));
    builds.push_back(build);
    totals.push_back(millisecondsSince(start));
  }
  r.total_ms = median(totals);
  r.build_ms = median(builds);
  r.slice_ms = median(slices);
  return r;
}

/// Every `stride`-th scan with its pose.
ScansWithPoses everyNth(const ScansWithPoses& data, size_t stride) {
  ScansWithPoses out;
  for (size_t k = 0; k < data.scans.size(); k += stride) {
    out.scans.push_back(data.scans[k]);
    out.poses.push_back(data.poses[k]);
  }
  return out;
}

/// OctoMap as the grid used it before: insertPointCloud per scan (lazy), then the inner nodes.
octomap::OcTree octomapGrid(const ScansWithPoses& data, const GridOptions& g) {
  octomap::OcTree tree(g.resolution);
  tree.setProbHit(g.prob_hit);
  tree.setProbMiss(g.prob_miss);
  tree.setClampingThresMin(g.clamp_min);
  tree.setClampingThresMax(g.clamp_max);
  const auto z = static_cast<float>(0.5 * g.resolution);
  for (size_t k = 0; k < data.scans.size(); ++k) {
    const LaserScan& scan = data.scans[k];
    const Pose2 sensor = data.poses[k] * scan.laser_pose;
    octomap::Pointcloud cloud;
    for (size_t i = 0; i < scan.size(); ++i) {
      if (!scan.valid(i)) continue;
      const Vec2 p = sensor.transform(scan.point(i));
      cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), z);
    }
    const double max_range = g.max_range > 0.0 ? g.max_range : scan.range_max;
    tree.insertPointCloud(cloud, octomap::point3d(static_cast<float>(sensor.x), static_cast<float>(sensor.y), z),
                          max_range, /*lazy_eval=*/true);
  }
  tree.updateInnerOccupancy();
  return tree;
}

/// Share of the cells known in either slice whose class (unknown / free / uncertain / occupied)
/// is the same in both, and the same for the cells occupied in either.
std::pair<double, double> agreement(const GridSlice& a, const GridSlice& b) {
  auto classOf = [](const GridSlice& s, int ix, int iy) {
    if (!s.inside(ix, iy) || !s.known(ix, iy)) return 0;
    return s.occupied(ix, iy) ? 3 : s.free(ix, iy) ? 1 : 2;
  };
  const auto first = [](const GridSlice& s) {
    return std::pair{static_cast<int>(std::lround(s.origin.x() / s.resolution)),
                     static_cast<int>(std::lround(s.origin.y() / s.resolution))};
  };
  const auto [ax, ay] = first(a);
  const auto [bx, by] = first(b);
  size_t known = 0, same = 0, occupied = 0, occupied_same = 0;
  for (int y = std::min(ay, by); y < std::max(ay + a.height, by + b.height); ++y)
    for (int x = std::min(ax, bx); x < std::max(ax + a.width, bx + b.width); ++x) {
      const int ca = classOf(a, x - ax, y - ay), cb = classOf(b, x - bx, y - by);
      if (ca == 0 && cb == 0) continue;
      ++known;
      same += ca == cb;
      if (ca == 3 || cb == 3) {
        ++occupied;
        occupied_same += ca == cb;
      }
    }
  return {known ? static_cast<double>(same) / known : 1.0, occupied ? static_cast<double>(occupied_same) / occupied : 1.0};
}

void compareWithOctomap(const ScansWithPoses& data, const Options& o, double raster_ms_per_scan) {
  const size_t stride = (data.scans.size() + o.octomap_scans - 1) / o.octomap_scans;  // spread over the whole run
  const ScansWithPoses subset = everyNth(data, stride);
  const auto start = Clock::now();
  const octomap::OcTree tree = octomapGrid(subset, o.grid);
  const double octomap_ms = millisecondsSince(start);
  const OccupancyGrid raster = buildGrid(subset.scans, subset.poses, o.grid);
  const auto [same_class, same_occupied] = agreement(raster.slice(), sliceOf(tree, raster.layerZ()));
  const double per_scan = octomap_ms / static_cast<double>(subset.scans.size());
  const std::string which = stride == 1 ? "all scans" : "every " + std::to_string(stride) + "th scan";
  std::printf("\nOctoMap insertPointCloud (what the grid used before), %s (%zu):\n", which.c_str(), subset.scans.size());
  std::printf("  %.2f ms per scan (raster: %.3f ms, %.0fx faster); %zu scans would take about %.0f ms\n", per_scan,
              raster_ms_per_scan, per_scan / raster_ms_per_scan, data.scans.size(),
              per_scan * static_cast<double>(data.scans.size()));
  std::printf("  raster vs OctoMap on those scans: %.3f %% of known cells in the same class, %.3f %% of occupied cells\n",
              100 * same_class, 100 * same_occupied);
}

void timeExport(const ScansWithPoses& data, const Options& o) {
  const OccupancyGrid grid = buildGrid(data.scans, data.poses, o.grid);
  const auto start = Clock::now();
  const auto tree = grid.toOcTree();
  std::printf("\nfor files only: toOcTree() (map.ot / map.bt) takes %.0f ms, %zu leaves\n", millisecondsSince(start),
              tree->getNumLeafNodes());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_grid_regeneration: buildGrid + slice for 2000 scans against the 200 ms goal"};
  Options o;
  app.add_option("--clf", o.clf, "CARMEN log (its odometry gives the poses)")->capture_default_str();
  app.add_flag("--simulate", o.simulate, "simulated scans even when the log exists");
  app.add_option("--world", o.world, "world for simulated scans")->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--robot", o.robot)->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--scans", o.scans)->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--repetitions", o.repetitions)->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--octomap-scans", o.octomap_scans, "about this many scans, spread over the run, for the OctoMap "
                 "comparison (0 = none)")->capture_default_str();
  app.add_option("--resolution", o.grid.resolution, "m")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--max-range", o.grid.max_range, "m; 0 = each scan's range_max (as polarslam-grid)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::optional<ScansWithPoses> carmen = fromCarmen(o);
  const ScansWithPoses data = carmen ? std::move(*carmen) : simulated(o);
  if (data.scans.empty()) {
    std::fprintf(stderr, "no scans\n");
    return 1;
  }
  const std::string max_range = o.grid.max_range > 0 ? std::to_string(o.grid.max_range) + " m" : "each scan's range_max";
  std::printf("grid regeneration: %zu scans from %s, %zu beams with a return; %.3f m cells, max range %s\n",
              data.scans.size(), data.source.c_str(), validBeams(data.scans), o.grid.resolution, max_range.c_str());
  const RegenerationTiming t = timeRegeneration(data, o);
  const double per_scan = t.build_ms / static_cast<double>(data.scans.size());
  std::printf("  grid %d x %d cells; median of %d: %.1f ms (buildGrid %.1f ms = %.3f ms per scan, slice %.1f ms)\n",
              t.slice.width, t.slice.height, o.repetitions, t.total_ms, t.build_ms, per_scan, t.slice_ms);
  const bool pass = t.total_ms < 200.0;
  std::printf("  goal buildGrid + slice < 200 ms: %s\n", pass ? "PASS" : "MISS");
  std::fflush(stdout);
  if (o.octomap_scans > 0) compareWithOctomap(data, o, per_scan);
  timeExport(data, o);
  return pass ? 0 : 1;
}
