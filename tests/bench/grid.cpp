// bench_grid: occupancy-grid consistency after loop closure (thesis §3.7.2, docs/algorithms.md §19.3).
// The simulated robot drives the default office path, which closes a loop; fused EKF SLAM runs
// over it and anchors every laser scan to the map features around it. After the run (the map
// has shifted at loop closure) three grids are built from the same anchored scans:
//   scan-time    the SLAM pose each scan had when it was taken,
//   regenerated  each pose re-solved from its anchors in the final map (§3.7.2),
//   truth        the simulator's ground-truth pose,
// and compared with the world's walls: occupied-cell precision (occupied cells within one cell
// of a true wall) and wall recall (length of laser-visible wall with an occupied cell within
// one cell). A SLAM map's absolute placement is arbitrary, so each grid is scored after the
// rigid transform that best aligns its poses with the true ones (as the aligned ATE does).
// Also: pose error of each pose set against ground truth (after the same alignment), how far
// regeneration moved the poses, and the time per scan insertion.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <filesystem>
#include <numeric>

#include "eval/ate.hpp"
#include "eval/trajectory_lookup.hpp"
#include "grid/anchored_scan_store.hpp"
#include "grid/grid_files.hpp"
#include "grid/pose_regeneration.hpp"
#include "sim/simulator.hpp"
#include "pipeline/feature_slam_estimator.hpp"

using namespace polarslam;

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string world = std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/office.yaml";
  std::string robot = std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml";
  int seeds = 3;
  uint64_t first_seed = 1;
  double resolution = 0.05;
  std::string sensors = "fused";
  std::string out;  ///< optional folder for the three grids of the first seed (PNG, PGM, BT)
  /// Odometry errors. The default robot's odometry is so good that the map hardly moves at loop
  /// closure; noisier wheels (σ² × noise_scale, which the EKF is told) make the map drift so
  /// that the loop closure shifts it — the situation pose regeneration is for. Systematic errors
  /// (unknown to the EKF) are available too, but make the EKF overconfident, so it does not
  /// correct its map at the loop closure and nothing can be regenerated.
  double radius_error = 0.0;      ///< both wheels' true radius = nominal · (1 + e)
  double wheel_base_error = 0.0;   ///< odometry computes with wheel_base · (1 + e)
  double noise_scale = 20.0;       ///< multiplies the per-wheel random error variances (known to the EKF)
};

/// Simulator output fed to the EKF; laser scans and ground truth kept for the grids.
class Recorder : public SimSink {
 public:
  explicit Recorder(FeatureSlamEstimator& ekf) : ekf_(ekf) {}
  void onLaser(const LaserScan& scan) override {
    ekf_.onLaser(scan);
    scans.push_back(scan);
  }
  void onSonar(const SonarScan& scan) override { ekf_.onSonar(scan); }
  void onOdometry(const OdometryReading& odometry) override { ekf_.onOdometry(odometry); }
  void onGroundTruth(const PoseStamped& pose) override { truth.push_back(pose); }
  std::vector<LaserScan> scans;
  std::vector<PoseStamped> truth;

 private:
  FeatureSlamEstimator& ekf_;
};

struct GridScore {
  double precision = 0.0, recall = 0.0;
  int occupied = 0;
  double pose_rmse = 0.0;        ///< m, position error of the poses the grid was built from
  double heading_rmse_deg = 0.0; ///< heading error of those poses
  Pose2 alignment;               ///< best rigid fit of the poses onto the truth (applied before scoring)
  double insert_ms = 0.0;        ///< mean time to ray-cast one scan
};

/// Walls whose distance to a point is looked up often: a coarse bucket grid over segments.
class WallDistance {
 public:
  explicit WallDistance(const World& world) : world_(world) {}
  double operator()(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const WallSegment& s : world_.segments()) {
      const Vec2 e = s.b - s.a;
      const double t = std::clamp((p - s.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (s.a + t * e - p).squaredNorm());
    }
    return std::sqrt(best);
  }

 private:
  const World& world_;
};

/// Precision and recall of a grid built in the map frame, compared in the world frame
/// (map frame = the robot's start pose in the world).
void scoreAgainstWalls(const GridSlice& slice, const World& world, const Pose2& map_in_world, GridScore& score) {
  const WallDistance distance(world);
  int near = 0;
  for (int y = 0; y < slice.height; ++y)
    for (int x = 0; x < slice.width; ++x) {
      if (!slice.occupied(x, y)) continue;
      ++score.occupied;
      near += distance(map_in_world.transform(slice.cellCenter(x, y))) <= slice.resolution;
    }
  score.precision = score.occupied > 0 ? static_cast<double>(near) / score.occupied : 0.0;
  // Recall: sample every laser-visible wall each 2 cm; covered if an occupied cell centre lies
  // within one cell of the sample.
  const Pose2 world_to_map = map_in_world.inverse();
  double total = 0.0, covered = 0.0;
  const double step = 0.02;
  for (const WallSegment& s : world.segments()) {
    if (!stopsRay(s.material, Sensor::Laser)) continue;
    const int n = std::max(1, static_cast<int>(s.length() / step));
    for (int i = 0; i < n; ++i) {
      const Vec2 p = world_to_map.transform(s.a + (s.b - s.a) * ((i + 0.5) / n));
      total += s.length() / n;
      int cx, cy;
      slice.cellOf(p, cx, cy);
      bool hit = false;
      for (int dy = -2; dy <= 2 && !hit; ++dy)
        for (int dx = -2; dx <= 2 && !hit; ++dx)
          hit = slice.inside(cx + dx, cy + dy) && slice.occupied(cx + dx, cy + dy) &&
                (slice.cellCenter(cx + dx, cy + dy) - p).norm() <= slice.resolution;
      if (hit) covered += s.length() / n;
    }
  }
  score.recall = total > 0 ? covered / total : 0.0;
}

double positionRmse(const std::vector<Pose2>& poses, const std::vector<Pose2>& truth) {
  double sum = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) sum += (poses[i].translation() - truth[i].translation()).squaredNorm();
  return poses.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(poses.size()));
}

double headingRmseDeg(const std::vector<Pose2>& poses, const std::vector<Pose2>& truth) {
  double sum = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) sum += std::pow(wrapAngle(poses[i].theta - truth[i].theta), 2);
  return poses.empty() ? 0.0 : rad2deg(std::sqrt(sum / static_cast<double>(poses.size())));
}

GridScore scoreGrid(const std::string& name, const std::vector<const LaserScan*>& scans,
                    const std::vector<Pose2>& poses, const std::vector<Pose2>& truth, const World& world,
                    const Pose2& map_in_world, const Options& o) {
  GridOptions g;
  g.resolution = o.resolution;
  const auto start = Clock::now();
  const OccupancyGrid grid = buildGrid(scans, poses, g);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  GridScore score;
  score.insert_ms = 1e3 * seconds / static_cast<double>(std::max<size_t>(1, scans.size()));
  const GridSlice slice = grid.slice();
  // The SLAM map's absolute placement is arbitrary (it hangs on the start pose); what matters
  // is its shape. Each grid is compared in the frame that best aligns its poses with the truth.
  std::vector<Vec2> from, to;
  for (size_t i = 0; i < poses.size(); ++i) {
    from.push_back(poses[i].translation());
    to.push_back(truth[i].translation());
  }
  const Pose2 alignment = alignRigid2d(from, to);
  std::vector<Pose2> aligned;
  for (const Pose2& p : poses) aligned.push_back(alignment * p);
  score.pose_rmse = positionRmse(aligned, truth);
  score.heading_rmse_deg = headingRmseDeg(aligned, truth);
  score.alignment = alignment;
  scoreAgainstWalls(slice, world, map_in_world * alignment, score);
  if (!o.out.empty()) {
    GridPicture picture;
    picture.title = name + " poses";
    PlotSeries path{name + " poses", {}, seriesColor(0), 1.0, 0};
    for (const Pose2& p : poses) path.points.push_back(p.translation());
    picture.paths.push_back(path);
    writeGridFiles(o.out, grid, slice, picture, "map_" + name);
  }
  return score;
}

struct SeedResult {
  GridScore scan_time, regenerated, truth;
  RegenerationSummary summary;
  size_t scans = 0;
  double sim_seconds = 0.0, regenerate_ms = 0.0;
};

SeedResult runSeed(uint64_t seed, const World& world, const RobotDescription& robot, const Options& o) {
  FeatureSlamEstimator ekf(configForRobot(robot, parseSlamSensors(o.sensors)));
  Recorder recorder(ekf);
  Simulator sim(world, robot, seed);
  while (sim.time() < 3600.0 && !sim.finished()) sim.step(recorder);
  ekf.flush();
  SeedResult r;
  r.sim_seconds = sim.time();

  // The same store the EKF pipeline and polarslam-grid keep.
  AnchoredScanStore store;
  std::map<int64_t, LaserScan*> by_utime;
  for (LaserScan& s : recorder.scans) by_utime[s.utime] = &s;
  for (const ScanAnchors& a : ekf.anchors())
    if (const auto it = by_utime.find(a.utime); it != by_utime.end()) store.add(std::move(*it->second), a);
  const FeatureMap map = ekf.slam().map();

  const Pose2 map_in_world = recorder.truth.front().pose;  // the map frame is the start pose
  const TrajectoryLookup truth(recorder.truth);
  std::vector<const LaserScan*> scans;
  std::vector<const ScanAnchors*> anchors;
  std::vector<Pose2> scan_time, true_poses;
  for (const AnchoredScan& s : store.scans()) {
    const auto t = truth.interpolate(s.scan.utime, 30000);
    if (!t) continue;
    scans.push_back(&s.scan);
    anchors.push_back(&s.anchors);
    scan_time.push_back(s.anchors.pose.pose);
    true_poses.push_back(map_in_world.inverse() * *t);
  }
  r.scans = scans.size();
  const auto start = Clock::now();
  const std::vector<RegeneratedPose> regenerated = regeneratePoses(anchors, map);
  r.regenerate_ms = 1e3 * std::chrono::duration<double>(Clock::now() - start).count();
  r.summary = summarize(anchors, regenerated);
  std::vector<Pose2> regenerated_poses;
  for (const RegeneratedPose& p : regenerated) regenerated_poses.push_back(p.pose);

  Options out = o;
  if (seed != o.first_seed) out.out.clear();
  r.scan_time = scoreGrid("scan_time", scans, scan_time, true_poses, world, map_in_world, out);
  r.regenerated = scoreGrid("regenerated", scans, regenerated_poses, true_poses, world, map_in_world, out);
  r.truth = scoreGrid("truth", scans, true_poses, true_poses, world, map_in_world, out);
  return r;
}

void printHeader() {
  std::printf("  %-12s %11s %11s %9s %11s %13s %10s\n", "poses", "precision", "recall", "occupied", "pose RMSE m",
              "heading RMSE", "insert ms");
}

void printRow(const char* name, const GridScore& s) {
  std::printf("  %-12s %9.1f %% %9.1f %% %9d %11.3f %11.2f ° %10.2f\n", name, 100 * s.precision, 100 * s.recall,
              s.occupied, s.pose_rmse, s.heading_rmse_deg, s.insert_ms);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_grid: scan-time vs regenerated vs ground-truth occupancy grids after loop closure"};
  Options o;
  app.add_option("--world", o.world)->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--robot", o.robot)->check(CLI::ExistingFile)->capture_default_str();
  app.add_option("--seeds", o.seeds)->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--first-seed", o.first_seed)->capture_default_str();
  app.add_option("--resolution", o.resolution, "m")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--sensors", o.sensors)->check(CLI::IsMember({"laser", "sonar", "fused"}))->capture_default_str();
  app.add_option("--radius-error", o.radius_error, "systematic wheel radius error (both wheels)")->capture_default_str();
  app.add_option("--wheel-base-error", o.wheel_base_error, "systematic wheel base error")->capture_default_str();
  app.add_option("--noise-scale", o.noise_scale, "scales the random wheel error variances")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--out", o.out, "folder for the first seed's three grids (map_<name>.{png,pgm,yaml,bt,ot})");
  CLI11_PARSE(app, argc, argv);

  const World world = loadWorld(o.world);
  RobotDescription robot = loadRobotDescription(o.robot);
  robot.odometry.left_radius_error = robot.odometry.right_radius_error = o.radius_error;
  // configForRobot() gives the EKF the scaled random error, not the systematic ones.
  robot.odometry.wheel_base_error = o.wheel_base_error;
  robot.odometry.k_left *= o.noise_scale;
  robot.odometry.k_right *= o.noise_scale;
  std::printf("bench_grid: world %s, %s EKF SLAM, %.3f m cells, %d seed(s); odometry: wheel radius error %+.3f, "
              "wheel base error %+.3f (unknown to the EKF), random wheel error variance x%.1f (known to it)\n",
              o.world.c_str(), o.sensors.c_str(), o.resolution, o.seeds, o.radius_error, o.wheel_base_error,
              o.noise_scale);
  std::vector<SeedResult> results;
  for (int k = 0; k < o.seeds; ++k) {
    const uint64_t seed = o.first_seed + static_cast<uint64_t>(k);
    const SeedResult r = runSeed(seed, world, robot, o);
    results.push_back(r);
    std::printf("\nseed %llu: %.0f s simulated, %zu anchored scans kept; regeneration: %d regenerated, %d chained, "
                "%d stored, %d anchors rejected, poses moved %.3f m mean / %.3f m max, %.2f ms per scan\n",
                static_cast<unsigned long long>(seed), r.sim_seconds, r.scans, r.summary.regenerated, r.summary.chained,
                r.summary.stored, r.summary.anchors_rejected, r.summary.mean_shift, r.summary.max_shift,
                r.regenerate_ms / static_cast<double>(std::max<size_t>(1, r.scans)));
    printHeader();
    printRow("scan-time", r.scan_time);
    printRow("regenerated", r.regenerated);
    printRow("truth", r.truth);
    std::fflush(stdout);
  }

  auto meanOf = [&](auto member, auto field) {
    double sum = 0.0;
    for (const SeedResult& r : results) sum += (r.*member).*field;
    return sum / static_cast<double>(results.size());
  };
  std::printf("\nmean over %zu seed(s)\n", results.size());
  printHeader();
  for (auto [name, member] : {std::pair{"scan-time", &SeedResult::scan_time},
                              std::pair{"regenerated", &SeedResult::regenerated}, std::pair{"truth", &SeedResult::truth}}) {
    GridScore mean;
    mean.precision = meanOf(member, &GridScore::precision);
    mean.recall = meanOf(member, &GridScore::recall);
    mean.occupied = static_cast<int>(meanOf(member, &GridScore::occupied));
    mean.pose_rmse = meanOf(member, &GridScore::pose_rmse);
    mean.heading_rmse_deg = meanOf(member, &GridScore::heading_rmse_deg);
    mean.insert_ms = meanOf(member, &GridScore::insert_ms);
    printRow(name, mean);
  }
  const double p_scan = meanOf(&SeedResult::scan_time, &GridScore::precision);
  const double p_regen = meanOf(&SeedResult::regenerated, &GridScore::precision);
  const double p_truth = meanOf(&SeedResult::truth, &GridScore::precision);
  const double r_scan = meanOf(&SeedResult::scan_time, &GridScore::recall);
  const double r_regen = meanOf(&SeedResult::regenerated, &GridScore::recall);
  const double r_truth = meanOf(&SeedResult::truth, &GridScore::recall);
  const bool beats = p_regen > p_scan && r_regen >= r_scan - 0.005;
  const bool close = p_truth - p_regen <= 0.05 && r_truth - r_regen <= 0.05;
  std::printf("\nregenerated beats scan-time: %s (precision %+.1f points, recall %+.1f points)\n", beats ? "yes" : "NO",
              100 * (p_regen - p_scan), 100 * (r_regen - r_scan));
  std::printf("regenerated within 5 points of ground truth: %s (precision %.1f points, recall %.1f points below)\n",
              close ? "yes" : "NO", 100 * (p_truth - p_regen), 100 * (r_truth - r_regen));
  return beats && close ? 0 : 1;
}
