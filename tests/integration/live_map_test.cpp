// The live polarslam-psm-slam with its map options (issue 15) next to `polarslam run` with the
// same ones: the default log played into the process with lcm-logplayer, what it publishes
// recorded with lcm-logger and scored like any recording. Mapping saves its map on a SAVE_MAP
// request and on exit; localising and continuing in that map give the offline numbers live.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <thread>

#include "child_process.hpp"
#include "map_files.hpp"
#include "common/lcm_log.hpp"
#include "map/map_store.hpp"
#include "pipeline/psm_slam_session.hpp"
#include "unit/slam/synthetic_run.hpp"
#include "polarslam/grid_status_t.hpp"
#include "polarslam/map_request_t.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::freshDir;
using polarslam::testing::readFile;
using polarslam::testing::figure;
using polarslam::testing::readJson;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;
using polarslam::testing::MapServerMap;
using polarslam::testing::occupiedAgreement;
using polarslam::testing::readMapServer;

namespace {
namespace fs = std::filesystem;

const std::string kLog = sourcePath("logs/office.lcmlog");
const std::string kConfig = sourcePath("config/psm-slam.yaml");

nlohmann::json runOffline(const fs::path& dir, const std::string& name, const std::vector<std::string>& options,
                          const std::string& config = kConfig) {
  std::vector<std::string> argv{binPath("polarslam"), "run",    "--log", kLog, "--pipeline", "psm-slam", "--config",
                                config,                "--out", (dir / ("offline-" + name)).string()};
  argv.insert(argv.end(), options.begin(), options.end());
  EXPECT_EQ(runToEnd(argv, dir / ("offline-" + name + ".out"), 300s), 0) << readFile(dir / ("offline-" + name + ".out"));
  return readJson(dir / ("offline-" + name) / "report.json");
}

void requestSave() {
  lcm::LCM lcm;
  polarslam::map_request_t request{};
  request.utime = 1;
  lcm.publish("SAVE_MAP", &request);
}

/// Plays the log into a live polarslam-psm-slam with `options`, records everything, stops the
/// process (its final graph and saved map), and scores the recorded PSM_SLAM_POSE. With
/// `grid_options`, a polarslam-grid --source psm-slam runs beside it and writes its map into
/// live-NAME-grid on exit.
nlohmann::json runLive(const fs::path& dir, const std::string& name, const std::vector<std::string>& options,
                       bool save_request = false, const std::optional<std::vector<std::string>>& grid_options = {},
                       const std::string& config = kConfig) {
  const std::string recorded = (dir / ("live-" + name + ".lcmlog")).string();
  ChildProcess logger({"lcm-logger", "--quiet", "--force", recorded}, (dir / ("logger-" + name + ".out")).string());
  std::unique_ptr<ChildProcess> grid;
  if (grid_options) {
    std::vector<std::string> argv{binPath("polarslam-grid"), "--source", "psm-slam", "--config", kConfig,
                                  "--out", (dir / ("live-" + name + "-grid")).string(), "--write-period", "0"};
    argv.insert(argv.end(), grid_options->begin(), grid_options->end());
    grid = std::make_unique<ChildProcess>(argv, (dir / ("grid-" + name + ".out")).string());
  }
  std::vector<std::string> argv{binPath("polarslam-psm-slam"), "--config", config};
  argv.insert(argv.end(), options.begin(), options.end());
  ChildProcess slam(argv, (dir / ("slam-" + name + ".out")).string());
  std::this_thread::sleep_for(1500ms);  // both subscribed before the first message
  ChildProcess player({"lcm-logplayer", "--speed", "8", kLog}, (dir / ("player-" + name + ".out")).string());
  if (save_request) {
    std::this_thread::sleep_for(8s);  // about half the log
    requestSave();
  }
  EXPECT_TRUE(player.waitFor(120s)) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(1s);
  slam.signal(SIGINT);
  EXPECT_TRUE(slam.waitFor(60s));
  EXPECT_EQ(slam.exitCode(), 0) << readFile(dir / ("slam-" + name + ".out"));
  if (grid) {
    std::this_thread::sleep_for(500ms);  // the final graph
    grid->signal(SIGINT);
    EXPECT_TRUE(grid->waitFor(60s));
    EXPECT_EQ(grid->exitCode(), 0) << readFile(dir / ("grid-" + name + ".out"));
  }
  logger.signal(SIGINT);
  EXPECT_TRUE(logger.waitFor(10s));
  const fs::path scored = dir / ("live-" + name);
  EXPECT_EQ(runToEnd({binPath("polarslam"), "run", "--log", recorded, "--pipeline", "recorded", "--pose-channel",
                      "PSM_SLAM_POSE", "--out", scored.string()},
                     dir / ("scored-" + name + ".out"), 120s),
            0)
      << readFile(dir / ("scored-" + name + ".out"));
  return readJson(scored / "report.json");
}

// The refinement (issue 19 item 1, refinement.enabled and .online, off by default) runs where the
// live process runs it, as `polarslam run` does: in the background after loop closures, its edges
// joining the graph at the next one, and at the end. With it on, the live final trajectory is the
// offline one, and so are the refinement's rounds and edges.
TEST(LiveMap, TheRefinementRunsLiveAsOffline) {
  const fs::path dir = freshDir("live-refinement");
  const std::string config = (dir / "psm-slam-refined.yaml").string();
  std::string text = readFile(kConfig);
  const size_t section = text.find("\nrefinement:");
  ASSERT_NE(section, std::string::npos) << "config/psm-slam.yaml has no refinement section";
  for (const std::string key : {"\n  enabled: false", "\n  online: false "}) {
    const size_t at = text.find(key, section);
    ASSERT_NE(at, std::string::npos) << "config/psm-slam.yaml's refinement section no longer has" << key;
    text.replace(at + key.find("false"), 5, "true ");
  }
  std::ofstream(config) << text;
  const nlohmann::json offline = runOffline(dir, "refined", {}, config);
  const nlohmann::json live = runLive(dir, "refined", {}, false, std::nullopt, config);
  const nlohmann::json& refinement = offline["psm_slam"]["refinement"];
  std::printf("refinement on           offline  live\n");
  std::printf("ATE RMSE, final [m]     %7.4f  %.4f\n", figure(offline, "ate_rmse_m"), figure(live, "ate_rmse_m"));
  std::printf("refinement edges        %7zu (%zu rounds after loop closures)\n", refinement.value("edges", size_t{0}),
              refinement.value("background_rounds", size_t{0}));
  EXPECT_GT(refinement.value("edges", size_t{0}), 50u) << offline["psm_slam"].dump();
  EXPECT_GT(refinement.value("background_rounds", size_t{0}), 0u) << offline["psm_slam"].dump();
  EXPECT_NEAR(figure(live, "ate_rmse_m"), figure(offline, "ate_rmse_m"), 0.10 * figure(offline, "ate_rmse_m"));
  const std::string edges = "refinement: " + std::to_string(refinement.value("edges", size_t{0})) + " edges of " +
                            std::to_string(refinement.value("pairs", size_t{0})) + " pairs matched (" +
                            std::to_string(refinement.value("background_rounds", size_t{0})) + " rounds";
  EXPECT_NE(readFile(dir / "slam-refined.out").find(edges), std::string::npos)
      << "live, the same refinement as offline (" << edges << "): " << readFile(dir / "slam-refined.out");
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

/// scans_stored of the last GRID_STATUS in a recorded log (-1: none).
int lastScansStored(const std::string& path) {
  polarslam::LcmLogReader reader(path);
  polarslam::LogEvent event;
  polarslam::grid_status_t status;
  int stored = -1;
  while (reader.next(event))
    if (event.channel == "GRID_STATUS" && event.decode(status)) stored = status.scans_stored;
  return stored;
}

/// Messages in an LCM log file (header included).
long eventsIn(const std::string& path) {
  polarslam::LcmLogReader reader(path);
  polarslam::LogEvent event;
  long n = 0;
  while (reader.next(event)) ++n;
  return n;
}

TEST(LiveMap, SavesLocalisesAndContinuesLiveAsOffline) {
  const fs::path dir = freshDir("live-map");
  const std::string live_map = (dir / "live-map").string(), offline_map = (dir / "offline-map").string();

  const nlohmann::json offline_mapping = runOffline(dir, "mapping", {"--save-map", offline_map});
  const nlohmann::json live_mapping = runLive(dir, "mapping", {"--save-map", live_map}, true);
  const std::string mapping_text = readFile(dir / "slam-mapping.out");
  EXPECT_NE(mapping_text.find("(request)"), std::string::npos) << "no save on the SAVE_MAP request:\n" << mapping_text;
  EXPECT_NE(mapping_text.find("(exit)"), std::string::npos) << mapping_text;
  ASSERT_EQ(runToEnd({binPath("polarslam"), "map-check", live_map}, dir / "check.out", 60s), 0) << readFile(dir / "check.out");
  EXPECT_NE(readFile(dir / "check.out").find(std::to_string(offline_mapping["saved_map"]["nodes"].get<int>()) + " "),
            std::string::npos)
      << "the live map has the offline map's node count (" << offline_mapping["saved_map"].dump() << "):\n"
      << readFile(dir / "check.out");

  // Both later runs work in the map the live process saved.
  const std::vector<std::string> localize{"--load-map", live_map, "--mode", "localize", "--initial-pose", "0,0,0"};
  const std::vector<std::string> extend{"--load-map", live_map, "--mode", "continue", "--initial-pose", "0,0,0"};
  const nlohmann::json offline_localize = runOffline(dir, "localize", localize);
  const nlohmann::json live_localize = runLive(dir, "localize", localize);
  const nlohmann::json offline_continue = runOffline(dir, "continue", extend);
  const nlohmann::json live_continue = runLive(dir, "continue", extend, false, std::vector<std::string>{"--load-map", live_map});

  std::printf("PSM SLAM, ATE RMSE [m]   offline final  live final  offline online  live online\n");
  for (const auto& [name, offline, live] :
       {std::tuple{"mapping", &offline_mapping, &live_mapping}, std::tuple{"localize", &offline_localize, &live_localize},
        std::tuple{"continue", &offline_continue, &live_continue}})
    std::printf("%-24s %13.4f  %10.4f  %14.4f  %11.4f\n", name, figure(*offline, "ate_rmse_m"), figure(*live, "ate_rmse_m"),
                figure(*offline, "online_ate_rmse_m"), figure(*live, "online_ate_rmse_m"));
  EXPECT_NEAR(figure(live_mapping, "ate_rmse_m"), figure(offline_mapping, "ate_rmse_m"),
              0.10 * figure(offline_mapping, "ate_rmse_m"));
  // Localising publishes poses while it runs and its final trajectory on exit (PSM_SLAM_PATH).
  EXPECT_NEAR(figure(live_localize, "ate_rmse_m"), figure(offline_localize, "ate_rmse_m"),
              0.10 * figure(offline_localize, "ate_rmse_m"));
  EXPECT_NEAR(figure(live_localize, "online_ate_rmse_m"), figure(offline_localize, "online_ate_rmse_m"),
              0.10 * figure(offline_localize, "online_ate_rmse_m"));
  EXPECT_EQ(live_localize["recorded"]["final_from"], "the final path published on exit") << live_localize.dump();
  EXPECT_NEAR(figure(live_continue, "ate_rmse_m"), figure(offline_continue, "ate_rmse_m"),
              0.10 * figure(offline_continue, "ate_rmse_m"));
  EXPECT_LT(figure(live_continue, "ate_rmse_m"), 0.10) << "in the map's frame";
  // The live grid of a continued map holds the stored scans and the new ones, as offline.
  const MapServerMap offline_grid = readMapServer(dir / "offline-continue");
  const MapServerMap live_grid = readMapServer(dir / "live-continue-grid");
  ASSERT_GT(offline_grid.occupied.size(), 100u);
  EXPECT_GE(occupiedAgreement(offline_grid, live_grid), 0.95);
  EXPECT_GE(occupiedAgreement(live_grid, offline_grid), 0.95);
  EXPECT_EQ(lastScansStored((dir / "live-continue.lcmlog").string()), offline_continue["grid"]["scans"].get<int>())
      << "the live grid keeps the map's reference scans and the new ones";
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

/// The scan of the first fix that a live polarslam-psm-slam reported on exit (-1: none).
long liveFirstFix(const std::string& output) {
  const std::string marker = "first fix at scan ";
  const size_t at = output.find(marker);
  return at == std::string::npos ? -1 : std::stol(output.substr(at + marker.size()));
}

// Global localisation live (issue 15, item 3): localising without --initial-pose, the process
// finds where it starts in the map by the global search, as `polarslam run` does offline with the
// same map, log and configuration: the same first fix, the same trajectory.
TEST(LiveMap, FindsAnUnknownStartLiveAsOffline) {
  const fs::path dir = freshDir("live-unknown-start");
  const std::string map = (dir / "map").string();
  runOffline(dir, "mapping", {"--save-map", map});
  const std::vector<std::string> localize{"--load-map", map, "--mode", "localize"};
  const nlohmann::json offline = runOffline(dir, "localize", localize);
  const nlohmann::json live = runLive(dir, "localize", localize);
  const long offline_fix = offline["localization"].value("first_fix_scan", -1L);
  const long live_fix = liveFirstFix(readFile(dir / "slam-localize.out"));
  std::printf("unknown start            offline  live\n");
  std::printf("first fix at scan        %7ld  %4ld\n", offline_fix, live_fix);
  std::printf("ATE RMSE, final [m]      %7.4f  %.4f\n", figure(offline, "ate_rmse_m"), figure(live, "ate_rmse_m"));
  std::printf("ATE RMSE, online [m]     %7.4f  %.4f\n", figure(offline, "online_ate_rmse_m"), figure(live, "online_ate_rmse_m"));
  ASSERT_GE(offline_fix, 0) << "offline, the start was never found: " << offline["localization"].dump();
  EXPECT_LT(offline_fix, 100) << offline["localization"].dump();
  EXPECT_NEAR(live_fix, offline_fix, 2) << readFile(dir / "slam-localize.out");
  EXPECT_NEAR(figure(live, "ate_rmse_m"), figure(offline, "ate_rmse_m"), 0.10 * figure(offline, "ate_rmse_m"));
  EXPECT_NEAR(figure(live, "online_ate_rmse_m"), figure(offline, "online_ate_rmse_m"),
              0.10 * figure(offline, "online_ate_rmse_m"));
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

/// A live run with --journal and a snapshot every 10 s of stream time, killed with SIGKILL after
/// about 80 s of the log and restarted; the recorded PSM_SLAM_POSE scored.
nlohmann::json killAndResume(const fs::path& dir, const std::string& name, const std::vector<std::string>& options) {
  const std::string journal = (dir / (name + ".journal")).string(), recorded = (dir / (name + ".lcmlog")).string();
  std::vector<std::string> slam_argv{binPath("polarslam-psm-slam"), "--config", kConfig, "--journal", journal,
                                     "--snapshot-period", "10"};
  slam_argv.insert(slam_argv.end(), options.begin(), options.end());
  const std::string out1 = (dir / (name + "-1.out")).string(), out2 = (dir / (name + "-2.out")).string();
  ChildProcess logger({"lcm-logger", "--quiet", "--force", recorded}, (dir / (name + "-logger.out")).string());
  auto slam = std::make_unique<ChildProcess>(slam_argv, out1);
  std::this_thread::sleep_for(1500ms);
  ChildProcess player({"lcm-logplayer", "--speed", "4", kLog}, (dir / (name + "-player.out")).string());
  std::this_thread::sleep_for(20s);  // about 80 s of the log: several snapshots taken
  slam->signal(SIGKILL);
  EXPECT_TRUE(slam->waitFor(10s));
  EXPECT_TRUE(fs::exists(journal + ".snapshot/resume.json")) << readFile(out1);
  const long journal_events = eventsIn(journal), played = eventsIn(recorded);
  std::printf("%s: killed after %ld recorded messages; the journal holds %ld\n", name.c_str(), played, journal_events);
  EXPECT_LT(journal_events, played / 4) << "the journal was not cut";
  // What the restart will resume, as map-check reads it.
  const fs::path check = dir / (name + "-check.out");
  EXPECT_EQ(runToEnd({binPath("polarslam"), "map-check", journal + ".snapshot"}, check, 60s), 0) << readFile(check);
  EXPECT_NE(readFile(check).find("crash-recovery snapshot: mode " + std::string(name == "mapping" ? "continue, a filter of"
                                                                                                     : "localize")),
            std::string::npos)
      << readFile(check);
  EXPECT_NE(readFile(check).find("resumable"), std::string::npos) << readFile(check);
  slam = std::make_unique<ChildProcess>(slam_argv, out2);
  EXPECT_TRUE(player.waitFor(120s));
  std::this_thread::sleep_for(1s);
  slam->signal(SIGINT);
  EXPECT_TRUE(slam->waitFor(60s));
  EXPECT_EQ(slam->exitCode(), 0) << readFile(out2);
  EXPECT_NE(readFile(out2).find("resuming from snapshot"), std::string::npos) << readFile(out2);
  logger.signal(SIGINT);
  EXPECT_TRUE(logger.waitFor(10s));
  const fs::path scored = dir / (name + "-scored");
  EXPECT_EQ(runToEnd({binPath("polarslam"), "run", "--log", recorded, "--pipeline", "recorded", "--pose-channel",
                      "PSM_SLAM_POSE", "--out", scored.string()},
                     dir / (name + "-scored.out"), 120s),
            0)
      << readFile(dir / (name + "-scored.out"));
  return readJson(scored / "report.json");
}

// Snapshots (issue 15, item 4): with --journal and --snapshot-period the process saves its map
// (localising: the map and the pose) every 10 s of stream time and cuts its journal. Killed with
// SIGKILL mid-run, the journal holds only the messages since the last snapshot; restarted, it
// resumes from the snapshot, and the final trajectory is as good as the undisturbed run's.
TEST(LiveMap, SnapshotsCutTheJournalAndARestartResumesFromThem) {
  const fs::path dir = freshDir("snapshots");
  const std::string map = (dir / "map").string();
  const nlohmann::json offline = runOffline(dir, "mapping", {"--save-map", map});
  const std::vector<std::string> localize{"--load-map", map, "--mode", "localize", "--initial-pose", "0,0,0"};
  const nlohmann::json offline_localize = runOffline(dir, "localize", localize);
  const nlohmann::json mapping = killAndResume(dir, "mapping", {});
  const nlohmann::json localizing = killAndResume(dir, "localize", localize);
  std::printf("PSM SLAM final ATE RMSE [m]  undisturbed (offline)  killed, resumed from a snapshot\n");
  std::printf("mapping                      %21.4f  %31.4f\n", figure(offline, "ate_rmse_m"), figure(mapping, "ate_rmse_m"));
  std::printf("localising                   %21.4f  %31.4f\n", figure(offline_localize, "ate_rmse_m"),
              figure(localizing, "ate_rmse_m"));
  EXPECT_LT(figure(mapping, "ate_rmse_m"), 1.10 * figure(offline, "ate_rmse_m"));
  // Localising: the resumed process's final path places the scans since the snapshot.
  EXPECT_LT(figure(localizing, "ate_rmse_m"), 1.10 * figure(offline_localize, "ate_rmse_m"));
  EXPECT_EQ(localizing["recorded"]["final_from"], "the final path published on exit") << localizing.dump();
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

// A snapshot that reads back but cannot be resumed (its filter state is not a covariance; the
// checksum fits, so it is no disk damage) is set aside as damaged, and the process starts from its
// journal alone instead of failing on every restart.
TEST(LiveMap, ASnapshotThatCannotBeResumedIsSetAsideAndTheProcessStarts) {
  const fs::path dir = freshDir("unresumable");
  const std::string journal = (dir / "psm.journal").string(), snapshot = journal + ".snapshot";
  const polarslam::testing::SyntheticRun run =
      polarslam::testing::simulateLoopRun(polarslam::testing::makeLoopWorld(), polarslam::testing::SyntheticRunOptions{});
  polarslam::PsmSlamSession session({}, {});
  for (size_t k = 0; k < run.scans.size() / 2; ++k) {
    session.onOdometry(run.odometry[k]);
    session.onLaser(run.scans[k]);
  }
  session.writeSnapshot(snapshot, {{"generation", 1}});
  polarslam::StoredMap map = polarslam::loadMap(snapshot);
  // resume-filter.bin: the mean (3n values), then the covariance's lower triangle by rows; its
  // element (1, 0) made a correlation far beyond 1.
  const size_t n = 3 * (nlohmann::json::parse(map.resume_json)["filter"]["keyframes"].size() + 1);
  const double beyond = 1e6;
  std::memcpy(map.resume_filter.data() + (n + 1) * sizeof(double), &beyond, sizeof(double));
  polarslam::saveMap(snapshot, map);

  const std::string out = (dir / "slam.out").string();
  ChildProcess slam({binPath("polarslam-psm-slam"), "--config", kConfig, "--journal", journal}, out);
  std::this_thread::sleep_for(3s);
  slam.signal(SIGINT);
  ASSERT_TRUE(slam.waitFor(30s));
  EXPECT_EQ(slam.exitCode(), 0) << readFile(out);
  EXPECT_NE(readFile(out).find("cannot be resumed"), std::string::npos) << readFile(out);
  EXPECT_TRUE(fs::exists(snapshot + ".damaged"));
  EXPECT_FALSE(fs::exists(snapshot + "/resume.json")) << "set aside, not resumed";
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
