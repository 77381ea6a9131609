#pragma once
// Process groups for polarslam-launch (the libbot2 procman model): a YAML file of nested groups
// of commands saying what to run, on which host, and how to stop and restart it. The format is
// documented in processes/polarslam-launch/README.md.
#include <csignal>
#include <map>
#include <string>
#include <vector>

namespace polarslam {

using Environment = std::map<std::string, std::string>;

/// Restart delays after consecutive crashes: initial, initial·factor, … up to max. A process that
/// ran for reset_after seconds before crashing counts as a first crash again.
struct RestartBackoff {
  double initial_s = 0.05;  // a stateless stage back within a scan period: little input lost
  double factor = 2.0;
  double max_s = 30.0;
  double reset_after_s = 10.0;

  /// Delay before the restart that follows crash number `consecutive_crashes` (1, 2, …).
  double delay(int consecutive_crashes) const;
};

struct CommandSpec {
  std::string name;                 // unique in the file; PROCESS_STATUS name and log file name
  std::string group_path;           // e.g. "pipeline/estimators"
  std::vector<std::string> argv;    // argv[0] is searched on PATH when it has no '/'
  Environment environment;          // set on top of the launcher's environment
  std::string working_dir;          // empty: the launcher's working directory
  std::string host;                 // empty: any host (started only when no --host is given)
  bool auto_respawn = true;         // restart after a crash (a signal or a non-zero exit)
  int stop_signal = SIGTERM;
  double stop_grace_s = 3.0;        // time between stop_signal and SIGKILL
  int start_order = 0;              // lower starts first; ties keep file order
  double start_delay_s = 0.0;       // wait after the previous command's start
  // The first start also waits until these commands have reported PROCESS_STATUS "running" (they
  // have subscribed: nothing they are to receive is lost), for wait_timeout_s at most.
  std::vector<std::string> wait_for;
  double wait_timeout_s = 30.0;
  bool required = false;            // when it ends for good, everything stops (e.g. a log player)
  RestartBackoff backoff;
  std::string where;                // "FILE:LINE" of its definition
};

struct GroupSpec {
  std::string name;
  std::string path;                 // names from the top group down, joined by '/'
  std::vector<CommandSpec> commands;
  std::vector<GroupSpec> groups;
};

/// Loads a group file. `${NAME}` in exec, args, working_dir and environment values is replaced
/// from `launcher_env`, GROUP_DIR (the file's folder) and the command's own environment.
/// Every error is a std::runtime_error "FILE:LINE: what is wrong".
GroupSpec loadGroupFile(const std::string& path, const Environment& launcher_env);

/// The commands of the group named `group` (empty: the whole file) and of its subgroups that
/// belong to `host` (empty: every command), in start order. Throws when nothing matches.
std::vector<CommandSpec> selectCommands(const GroupSpec& root, const std::string& group,
                                        const std::string& host);

/// Replaces `${NAME}` from `vars`; throws "WHERE: unknown variable ${NAME}" otherwise.
std::string expandVariables(const std::string& text, const Environment& vars, const std::string& where);

/// "a, b, c": names in a message.
std::string joined(const std::vector<std::string>& words);

/// "SIGINT", "INT", "int" or "2" → 2; -1 when not a signal a process can be stopped with.
int parseSignal(const std::string& text);
/// "SIGINT" for 2.
std::string signalName(int signal);

}  // namespace polarslam
