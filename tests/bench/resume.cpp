// bench_resume: how well PSM SLAM resumes after a crash (issue 15, item 4), in-process and
// deterministic. Per seed of the simulated office, a run snapshots every --period s of stream time
// (as polarslam-psm-slam --snapshot-period does), is killed at --kill s, loses the messages of the
// next --gap s (the restart's downtime), and resumes from its last snapshot with the messages
// since it (what the cut journal holds). Prints the final trajectory's error from the snapshot
// on, resumed and undisturbed (the same run without the kill), against ground truth.
//
//   bench_resume [--seeds 10] [--kill 75] [--gap 6] [--config config/psm-slam.yaml]
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>

#include "eval/ate.hpp"
#include "session_recording.hpp"

using namespace polarslam;
namespace fs = std::filesystem;

namespace {

double ateOf(const std::vector<PoseStamped>& estimate, const std::vector<PoseStamped>& truth, int64_t from) {
  std::vector<PoseStamped> kept;
  for (const PoseStamped& p : estimate)
    if (p.utime >= from) kept.push_back(p);
  return evaluateAte(kept, truth).raw_translation.rmse;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_resume: PSM SLAM killed, restarted after a downtime, and resumed from its snapshot"};
  double kill = 75.0, period = 10.0, gap = 4.0;
  int seeds = 10, first_seed = 1;
  std::string config_path = std::string(POLARSLAM_SOURCE_DIR) + "/config/psm-slam.yaml";
  std::string world_path = std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/office.yaml";
  app.add_option("--kill", kill, "s of stream time when the process is killed")->capture_default_str();
  app.add_option("--period", period, "s of stream time between snapshots")->capture_default_str();
  app.add_option("--gap", gap, "s of messages lost while it restarts")->capture_default_str();
  app.add_option("--seeds", seeds)->capture_default_str();
  app.add_option("--first-seed", first_seed)->capture_default_str();
  app.add_option("--config", config_path, "PSM SLAM parameters")->capture_default_str();
  app.add_option("--world", world_path)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const PsmSlamEstimatorConfig config = loadPsmSlamEstimatorConfig(config_path);
  double sum_u = 0, sum_r = 0;
  for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
    World world = loadWorld(world_path);
    Simulator sim(world, loadRobotDescription(std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml"),
                  static_cast<uint64_t>(seed));
    testing::SessionRecording rec;
    while (!sim.finished()) sim.step(rec);
    rec.truth = inStartFrame(rec.truth);
    PsmSlamSession undisturbed(config, {});
    for (size_t k = 0; k < rec.messages.size(); ++k) rec.feed(undisturbed, k);
    undisturbed.finish();

    const fs::path dir = fs::temp_directory_path() / ("polarslam-resume-exp-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string snapshot_dir = (dir / "snap").string();
    PsmSlamSession first(config, {});
    const int64_t t0 = rec.utime(0);
    int64_t last_snapshot = 0;
    size_t snapshot_index = 0, k = 0;
    for (; k < rec.messages.size(); ++k) {
      if (rec.utime(k) - t0 > static_cast<int64_t>(kill * 1e6)) break;
      rec.feed(first, k);
      const auto* scan = std::get_if<LaserScan>(&rec.messages[k]);
      if (!scan || !first.canSnapshot()) continue;
      if (last_snapshot == 0) last_snapshot = scan->utime;
      if (scan->utime - last_snapshot < static_cast<int64_t>(period * 1e6)) continue;
      first.writeSnapshot(snapshot_dir, {{"generation", 1}});
      snapshot_index = k + 1;
      last_snapshot = scan->utime;
    }
    const std::optional<SessionSnapshot> snapshot = readSessionSnapshot(snapshot_dir, {});
    PsmSlamSession resumed(config, snapshot->options);
    if (snapshot->last_odometry) resumed.onOdometry(*snapshot->last_odometry);
    for (size_t i = snapshot_index; i < k; ++i) rec.feed(resumed, i);  // the journal
    const int64_t back = rec.utime(k) + static_cast<int64_t>(gap * 1e6);
    for (size_t i = k; i < rec.messages.size(); ++i)
      if (rec.utime(i) >= back) rec.feed(resumed, i);
    const nlohmann::json report = resumed.finish();
    const int64_t from = resumed.finalTrajectory().front().utime;
    const double u = ateOf(undisturbed.finalTrajectory(), rec.truth, from);
    const double r = ateOf(resumed.finalTrajectory(), rec.truth, from);
    const double u_all = ateOf(undisturbed.finalTrajectory(), rec.truth, 0);
    std::printf("seed %3d: from the snapshot at %5.1f s: undisturbed %.4f m (whole run %.4f m), resumed %.4f m (%.2fx); "
                "%d loop closures after the restart\n",
                seed, 1e-6 * static_cast<double>(from - t0), u, u_all, r, r / u,
                report["psm_slam"]["loop_closures"].get<int>());
    sum_u += u;
    sum_r += r;
    fs::remove_all(dir);
  }
  std::printf("mean over %d seeds: undisturbed %.4f m, resumed %.4f m (%.2fx)\n", seeds, sum_u / seeds, sum_r / seeds,
              sum_r / sum_u);
  return 0;
}
