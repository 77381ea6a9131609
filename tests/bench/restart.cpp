// bench_restart: issue 15's crash-recovery goal, a restart after a 2 h run in under 5 s. The
// simulated office is driven round and round for --hours of simulated time through the session
// polarslam-psm-slam runs (core/pipeline/psm_slam_session.hpp), taking a snapshot every
// --period seconds as the live process does; then a restart is timed: the last snapshot read
// back, the session built from it, and the messages since it (what the cut journal holds)
// replayed. Prints the snapshot's size and write time, the journal's bound and the restart time
// next to the goal, and the restart without snapshots (the whole run replayed) for comparison.
//
//   bench_restart [--hours 2] [--period 60] [--world config/worlds/office.yaml]
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "io/stopwatch.hpp"
#include "session_recording.hpp"

using namespace polarslam;
namespace fs = std::filesystem;

namespace {

uint64_t folderBytes(const fs::path& dir) {
  uint64_t bytes = 0;
  for (const auto& entry : fs::directory_iterator(dir)) bytes += entry.file_size();
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_restart: restart time of polarslam-psm-slam after a long run, with snapshots"};
  double hours = 2.0, period = 60.0;
  std::string world_path = std::string(POLARSLAM_SOURCE_DIR) + "/config/worlds/office.yaml";
  app.add_option("--hours", hours, "simulated run length")->capture_default_str();
  app.add_option("--period", period, "s of stream time between snapshots")->capture_default_str();
  app.add_option("--world", world_path, "simulated world (its path is driven in a loop)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  World world = loadWorld(world_path);
  world.path.loop = true;
  Simulator sim(world, loadRobotDescription(std::string(POLARSLAM_SOURCE_DIR) + "/config/robots/default.yaml"), 1);
  testing::SessionRecording recorder;
  auto start = std::chrono::steady_clock::now();
  while (sim.time() < hours * 3600.0) sim.step(recorder);
  std::printf("simulated %.1f h of %s: %zu messages in %.1f s\n", sim.time() / 3600.0, world_path.c_str(),
              recorder.messages.size(), secondsSince(start));

  const PsmSlamEstimatorConfig config = loadPsmSlamEstimatorConfig(std::string(POLARSLAM_SOURCE_DIR) + "/config/psm-slam.yaml");
  const fs::path dir = fs::temp_directory_path() / ("polarslam-bench-restart-" + std::to_string(::getpid()));
  const std::string snapshot_dir = (dir / "psm.journal.snapshot").string();
  fs::create_directories(dir);
  PsmSlamSession session(config, {});
  size_t since_snapshot = 0, snapshots = 0, longest_journal = 0;
  double snapshot_seconds = 0.0, worst_snapshot = 0.0;
  int64_t last_snapshot = 0;
  start = std::chrono::steady_clock::now();
  for (size_t k = 0; k < recorder.messages.size(); ++k) {
    recorder.feed(session, k);
    ++since_snapshot;
    const auto* scan = std::get_if<LaserScan>(&recorder.messages[k]);
    if (!scan || !session.canSnapshot()) continue;
    if (last_snapshot == 0) last_snapshot = scan->utime;
    if (scan->utime - last_snapshot < static_cast<int64_t>(period * 1e6)) continue;
    const auto t = std::chrono::steady_clock::now();
    session.writeSnapshot(snapshot_dir, {{"generation", snapshots + 1}, {"journal_events", since_snapshot}, {"utime", scan->utime}});
    const double took = secondsSince(t);
    snapshot_seconds += took;
    worst_snapshot = std::max(worst_snapshot, took);
    ++snapshots;
    longest_journal = std::max(longest_journal, since_snapshot);
    since_snapshot = 0;
    last_snapshot = scan->utime;
  }
  const double run_seconds = secondsSince(start);
  const size_t nodes = session.slam() ? session.slam()->graph().nodes().size() : 0;
  std::printf("run: %.1f s (%.0fx real time), %zu reference scans; %zu snapshots, %.3f s each on average, %.3f s the "
              "longest, %.1f MB each\n",
              run_seconds, sim.time() / run_seconds, nodes, snapshots, snapshots ? snapshot_seconds / snapshots : 0.0,
              worst_snapshot, folderBytes(snapshot_dir) / 1e6);
  std::printf("journal: at most %zu messages between cuts (the whole run: %zu)\n", longest_journal,
              recorder.messages.size());

  // The restart: read the snapshot, build the session, replay the journal since the snapshot.
  start = std::chrono::steady_clock::now();
  const std::optional<SessionSnapshot> snapshot = readSessionSnapshot(snapshot_dir, {});
  PsmSlamSession resumed(config, snapshot->options);
  if (snapshot->last_odometry) resumed.onOdometry(*snapshot->last_odometry);
  for (size_t i = recorder.messages.size() - since_snapshot; i < recorder.messages.size(); ++i)
    recorder.feed(resumed, i);
  const double restart = secondsSince(start);
  std::printf("%-58s %10s %10s\n", "figure", "measured", "goal");
  std::printf("%-58s %9.2fs %10s\n", "restart after the run (snapshot + journal since)", restart, "< 5 s");
  std::printf("%-58s %9.2fs %10s\n", "restart without snapshots (the whole journal replayed)", run_seconds, "");
  fs::remove_all(dir);
  return 0;
}
