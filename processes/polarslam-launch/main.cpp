// polarslam-launch GROUPS.yaml [--group NAME] [--host NAME] [--no-tui]: starts a process group
// (config/groups/*.yaml), keeps each process's output, restarts crashed processes with back-off,
// publishes PROCESS_STATUS for each, shows a live status table, and on SIGINT/SIGTERM stops them
// all with no process left behind. One launcher per host; see README.md in this folder.
#include <CLI/CLI.hpp>
#include <sys/prctl.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <string>

#include "common/program_info.hpp"
#include "common/process_context.hpp"
#include "console.hpp"
#include "launch/group_file.hpp"
#include "run_logs.hpp"
#include "status_channel.hpp"
#include "supervisor.hpp"

extern char** environ;

using namespace polarslam;

namespace {

std::string launchId(const std::string& host) {
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return host + "-" + std::to_string(getpid()) + "-" +
         std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(now).count());
}

Environment currentEnvironment() {
  Environment env;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    const size_t eq = entry.find('=');
    if (eq != std::string::npos) env[entry.substr(0, eq)] = entry.substr(eq + 1);
  }
  return env;
}

/// The launcher's own folder, put first on the children's PATH: the sibling polarslam-* programs.
std::string launcherBinDir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? "" : exe.parent_path().string();
}

bool stdoutIsAScreen() {
  const char* term = std::getenv("TERM");
  return isatty(STDOUT_FILENO) && term && std::string(term) != "dumb";
}

void printCommands(const std::vector<CommandSpec>& commands) {
  for (const auto& c : commands) {
    std::cout << c.name << "  host=" << (c.host.empty() ? "(any)" : c.host) << "  group=" << c.group_path << "  ";
    for (const auto& a : c.argv) std::cout << ' ' << a;
    std::cout << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"polarslam-launch: starts, watches and restarts a group of processes"};
  addVersionFlag(app);
  std::string file, group, host, run_dir, url;
  bool no_tui = false, list = false;
  double status_period = 5.0;
  app.add_option("groups", file, "group file (YAML), e.g. config/groups/pipeline.yaml")->required();
  app.add_option("--group", group, "start only this group (and its subgroups)");
  app.add_option("--host", host, "start only the commands of this host (one launcher per host)");
  app.add_flag("--no-tui", no_tui, "plain prefixed output lines even on a terminal");
  app.add_option("--run-dir", run_dir, "folder for the logs (default: ~/.local/state/polarslam/launch/DATE-HOST-PID)");
  app.add_option("--lcm-url", url, "LCM URL for PROCESS_STATUS, also given to the commands as LCM_DEFAULT_URL");
  app.add_option("--status-period", status_period, "seconds between status tables in plain output")
      ->check(CLI::PositiveNumber)->capture_default_str();
  app.add_flag("--list", list, "print the selected commands and exit");
  CLI11_PARSE(app, argc, argv);

  try {
    const Environment env = currentEnvironment();
    const std::vector<CommandSpec> commands = selectCommands(loadGroupFile(file, env), group, host);
    if (list) {
      printCommands(commands);
      return 0;
    }
    const std::string host_label = host.empty() ? hostName() : host;
    Environment child_env = env;
    if (!url.empty()) child_env["LCM_DEFAULT_URL"] = url;
    StatusChannel status(resolveLcmUrl(url), host_label);
    RunLogs logs(run_dir.empty() ? defaultRunDir(host_label) : run_dir);
    child_env["POLARSLAM_RUN_DIR"] = std::filesystem::absolute(logs.dir()).string();
    // Each launch has its own identity: a journal left in a reused run folder by an earlier launch
    // is stale and its stage refuses to replay it (processes/common/input_journal.hpp).
    child_env["POLARSLAM_LAUNCH_ID"] = launchId(host_label);
    // Orphaned descendants come to the launcher instead of init, so none can outlive it unseen.
    prctl(PR_SET_CHILD_SUBREAPER, 1);
    const bool live_table = !no_tui && stdoutIsAScreen();
    const std::string title = "polarslam-launch  " + file + (group.empty() ? "" : "  group " + group) + "  host " +
                              host_label + "  logs " + logs.dir();
    Console console(live_table, title, status_period);
    Supervisor supervisor(commands, child_env, launcherBinDir(), logs, console, status);
    const int code = supervisor.run();
    console.finish(supervisor.table(), LaunchClock::now());
    return code;
  } catch (const std::exception& e) {
    std::cerr << "polarslam-launch: " << e.what() << "\n";
    return 2;
  }
}
