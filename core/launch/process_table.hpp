#pragma once
// What polarslam-launch knows about each supervised command: its state, pid, restarts and when
// it is due to (re)start. Pure bookkeeping: the launcher does the forking, signalling and waiting
// and tells the table what happened; the table decides what happens next.
#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "launch/group_file.hpp"

namespace polarslam {

using LaunchClock = std::chrono::steady_clock;

enum class RunState {
  Scheduled,   // waiting for its first start
  Running,
  Restarting,  // crashed; a restart is scheduled after the back-off delay
  Stopping,    // stop signal sent; SIGKILL follows at kill_deadline
  Stopped,     // ended cleanly or stopped by the launcher
  Crashed,     // crashed and not restarted (auto_respawn off, or shutting down)
  Failed,      // could not be started (missing executable, exec error)
};

/// The word used in PROCESS_STATUS.state and the status table.
std::string stateName(RunState state);

/// How a process ended, from waitpid's status.
struct ExitStatus {
  bool signaled = false;
  int code = 0;  // exit code, or signal number when signaled

  static ExitStatus fromWaitStatus(int wait_status);
  bool clean() const { return !signaled && code == 0; }
  std::string describe() const;  // "exit 0", "exit 3", "killed by SIGKILL"
};

struct ProcessRecord {
  CommandSpec spec;
  RunState state = RunState::Scheduled;
  int pid = -1;  // also its process group id; -1 when not running
  int restarts = 0;
  int consecutive_crashes = 0;
  LaunchClock::time_point started_at{};
  LaunchClock::time_point next_start{};     // Scheduled, Restarting
  LaunchClock::time_point kill_deadline{};  // Stopping
  std::string last_exit;                    // ExitStatus::describe() of the latest end
  std::string error;                        // why it Failed
  bool reported_running = false;            // its program said PROCESS_STATUS "running" since its start
  double cpu_percent = 0.0;
  double rss_mb = 0.0;
};

class ProcessTable {
 public:
  /// Schedules the first starts: each command `start_delay` after the previous one.
  ProcessTable(std::vector<CommandSpec> commands, LaunchClock::time_point launch_time);

  const std::vector<ProcessRecord>& records() const { return records_; }
  const ProcessRecord& operator[](size_t i) const { return records_[i]; }
  size_t size() const { return records_.size(); }
  std::optional<size_t> indexOfPid(int pid) const;

  /// Commands whose (re)start is due at `now`: start_delay passed, and for a first start, every
  /// command of its wait_for reported running (or wait_timeout passed).
  std::vector<size_t> dueToStart(LaunchClock::time_point now) const;
  /// The earliest time a pending (re)start may become due, if any.
  std::optional<LaunchClock::time_point> nextStart(LaunchClock::time_point now) const;
  /// The commands of i's wait_for that have not yet reported running and still may (running or
  /// about to start). Commands not selected here (another host) are not waited for.
  std::vector<std::string> awaited(size_t i) const;
  /// The program of running command i reported PROCESS_STATUS "running": it is ready for input.
  void reportedRunning(size_t i);

  void started(size_t i, int pid, LaunchClock::time_point now);
  void startFailed(size_t i, const std::string& error);
  /// Records the end of process i; returns its new state (Restarting, Crashed or Stopped).
  RunState exited(size_t i, ExitStatus status, LaunchClock::time_point now);
  /// Stop requested for a running process; SIGKILL is due `stop_grace` later.
  void stopping(size_t i, LaunchClock::time_point now);
  /// Cancels every pending (re)start, for shutdown.
  void cancelPendingStarts();
  /// The running commands to stop next: those of the highest start_order, because the stop
  /// order is the reverse of the start order. Empty when nothing runs.
  std::vector<size_t> nextToStop() const;
  /// Every running command.
  std::vector<size_t> running() const;
  void setUsage(size_t i, double cpu_percent, double rss_mb);

  /// True while anything runs, stops or waits to (re)start.
  bool anyActive() const;
  /// True if any command crashed for good or failed to start.
  bool anyFailed() const;

 private:
  /// A first start held back by wait_for at `now`.
  bool waiting(size_t i, LaunchClock::time_point now) const;

  std::vector<ProcessRecord> records_;
  bool shutting_down_ = false;
};

}  // namespace polarslam
