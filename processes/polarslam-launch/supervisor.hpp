#pragma once
// The launcher's main loop: starts the selected commands on schedule, forwards and logs their
// output, restarts crashed ones with back-off, publishes their status, and on SIGINT/SIGTERM/
// SIGHUP stops them all (stop signal, grace, SIGKILL), in reverse start order, level by level,
// and waits until no descendant is left.
#include <map>
#include <string>
#include <vector>

#include "console.hpp"
#include "launch/line_splitter.hpp"
#include "launch/process_table.hpp"
#include "run_logs.hpp"
#include "signal_pipe.hpp"
#include "status_channel.hpp"

namespace polarslam {

class Supervisor {
 public:
  Supervisor(std::vector<CommandSpec> commands, Environment base_env, std::string bin_dir, RunLogs& logs,
             Console& console, StatusChannel& status);
  /// Runs until every command has ended, or until a stop signal has been handled and every
  /// process is gone. Returns 0, or 1 if a command failed to start or crashed for good.
  int run();
  const ProcessTable& table() const { return table_; }

 private:
  struct OutputStream {
    std::string name;
    int fd;
    LineSplitter splitter;
  };
  /// A process group asked to stop (or whose leader has died): SIGKILL at `deadline` if not empty.
  struct EndingGroup {
    std::string name;
    LaunchClock::time_point deadline;
    bool killed = false;
  };
  struct UsageSample {
    int pid = -1;
    uint64_t ticks = 0;
    LaunchClock::time_point at;
  };

  void startDue(LaunchClock::time_point now);
  void receiveReports();
  void start(size_t i, LaunchClock::time_point now);
  void waitForEvents(LaunchClock::time_point now);
  LaunchClock::time_point nextWakeup(LaunchClock::time_point now) const;
  void handleSignals(LaunchClock::time_point now);
  void readOutput(bool until_end);
  bool readStream(OutputStream& stream, bool until_end);  // false at end of stream
  void emitLine(const std::string& name, const std::string& text);
  void reapChildren(LaunchClock::time_point now);
  void onExit(size_t i, ExitStatus status, LaunchClock::time_point now);
  void beginShutdown(LaunchClock::time_point now);
  void stopNextLevel(LaunchClock::time_point now);
  void signalToStop(size_t i, int sig, LaunchClock::time_point now);
  void killAll(LaunchClock::time_point now);
  void enforceDeadlines(LaunchClock::time_point now);
  void killStrayDescendants();
  void sampleUsage(LaunchClock::time_point now);
  void publish(size_t i);
  void publishAll();
  void event(const std::string& text);
  bool finished() const;

  ProcessTable table_;
  Environment base_env_;
  std::string bin_dir_;
  RunLogs& logs_;
  Console& console_;
  StatusChannel& status_;
  SignalPipe signals_;
  std::vector<OutputStream> streams_;
  std::map<int, EndingGroup> ending_;  // by process group id
  std::map<size_t, UsageSample> usage_;
  LaunchClock::time_point next_status_;
  bool shutting_down_ = false;
  bool required_failed_ = false;  // a required command ended with a failure
  LaunchClock::time_point shutdown_began_{};
};

}  // namespace polarslam
