#include "supervisor.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>

#include "launch/proc_stats.hpp"
#include "spawn.hpp"

namespace polarslam {
namespace {

using namespace std::chrono_literals;

constexpr auto kStatusPeriod = 1s;
constexpr auto kGroupCheckPeriod = 50ms;  // how often an ending process group is checked for emptiness
constexpr size_t kReadChunk = 65536;
constexpr int kMaxChunksPerWakeup = 16;  // one chatty process must not starve the loop
constexpr auto kRepeatedSignalWindow = 500ms;

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2g s", s);
  return buf;
}

bool processGroupExists(int pgid) { return kill(-pgid, 0) == 0 || errno != ESRCH; }

/// Signals a leader's process group; the leader alone if it has moved to a group of its own.
void signalGroup(int pgid, int sig) {
  if (kill(-pgid, sig) != 0) kill(pgid, sig);
}

}  // namespace

Supervisor::Supervisor(std::vector<CommandSpec> commands, Environment base_env, std::string bin_dir,
                       RunLogs& logs, Console& console, StatusChannel& status)
    : table_(std::move(commands), LaunchClock::now()),
      base_env_(std::move(base_env)),
      bin_dir_(std::move(bin_dir)),
      logs_(logs),
      console_(console),
      status_(status),
      next_status_(LaunchClock::now()) {}

int Supervisor::run() {
  event("logs in " + logs_.dir());
  while (true) {
    const auto now = LaunchClock::now();
    if (!shutting_down_) startDue(now);
    if (now >= next_status_) {
      sampleUsage(now);
      publishAll();
      next_status_ = now + kStatusPeriod;
    }
    console_.refresh(table_, now);
    logs_.flush();
    if (finished()) break;
    waitForEvents(now);
    handleSignals(LaunchClock::now());
    receiveReports();
    readOutput(false);
    reapChildren(LaunchClock::now());
    enforceDeadlines(LaunchClock::now());
    if (shutting_down_ && ending_.empty()) stopNextLevel(LaunchClock::now());
  }
  if (!shutting_down_) event("every command has ended");
  killStrayDescendants();
  readOutput(true);
  publishAll();
  logs_.flush();
  return table_.anyFailed() || required_failed_ ? 1 : 0;
}

bool Supervisor::finished() const { return !table_.anyActive() && ending_.empty(); }

void Supervisor::startDue(LaunchClock::time_point now) {
  for (size_t i : table_.dueToStart(now)) {
    if (const auto late = table_.awaited(i); !late.empty() && table_[i].state == RunState::Scheduled)
      event(table_[i].spec.name + ": " + joined(late) + " did not report running within wait_timeout (" +
            seconds(table_[i].spec.wait_timeout_s) + "): starting it anyway");
    start(i, now);
  }
}

// A process's own "running" report: it has subscribed. The launcher's own messages name the
// command, the process's own its program; both carry the pid of the command's process group.
void Supervisor::receiveReports() {
  for (const process_status_t& report : status_.receive()) {
    if (report.state != "running" || report.pid <= 0) continue;
    const auto i = table_.indexOfPid(getpgid(report.pid));
    if (i && report.name != table_[*i].spec.name) table_.reportedRunning(*i);
  }
}

void Supervisor::start(size_t i, LaunchClock::time_point now) {
  const CommandSpec& spec = table_[i].spec;
  SpawnResult spawned = spawnCommand(spec, base_env_, bin_dir_);
  if (spawned.pid < 0) {
    table_.startFailed(i, spawned.error);
    event("ERROR " + spec.name + " (" + spec.where + "): " + spawned.error +
          (spawned.detail.empty() ? "" : " (" + spawned.detail + ")") + "; the other commands keep running");
    publish(i);
    return;
  }
  const bool restart = table_[i].state == RunState::Restarting;
  table_.started(i, spawned.pid, now);
  streams_.push_back({spec.name, spawned.output_fd, LineSplitter()});
  const std::string what = "started " + spec.name + " (pid " + std::to_string(spawned.pid) +
                           (restart ? ", restart " + std::to_string(table_[i].restarts) : "") + ")";
  event(what);
  logs_.write(spec.name, "[launch] " + what);
  publish(i);
}

LaunchClock::time_point Supervisor::nextWakeup(LaunchClock::time_point now) const {
  LaunchClock::time_point wake = std::min(next_status_, console_.nextRefresh());
  if (const auto next = table_.nextStart(now); next && !shutting_down_) wake = std::min(wake, *next);
  if (!ending_.empty()) wake = std::min(wake, now + kGroupCheckPeriod);
  return wake;
}

void Supervisor::waitForEvents(LaunchClock::time_point now) {
  std::vector<pollfd> fds{{signals_.fd(), POLLIN, 0}, {status_.fd(), POLLIN, 0}};
  for (const auto& s : streams_) fds.push_back({s.fd, POLLIN, 0});
  const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(nextWakeup(now) - now);
  // Round up so the loop does not spin in the last fraction of a millisecond before a deadline.
  const int timeout_ms = static_cast<int>(std::clamp<int64_t>(wait.count() + 1, 0, 1000));
  poll(fds.data(), fds.size(), timeout_ms);
}

void Supervisor::handleSignals(LaunchClock::time_point now) {
  for (int sig : signals_.drain()) {
    if (sig == SIGWINCH) {
      console_.refresh(table_, now, true);
    } else if (sig == SIGINT || sig == SIGTERM || sig == SIGHUP) {
      if (!shutting_down_) {
        event("received " + signalName(sig) +
              ": stopping everything in reverse start order (send it again to kill at once)");
        beginShutdown(now);
        shutdown_began_ = now;
      } else if (now - shutdown_began_ < kRepeatedSignalWindow) {
        // The same stop often arrives twice at once (timeout(1), kill of the whole process group):
        // only a later, deliberate repeat means "kill now".
      } else {
        event("received " + signalName(sig) + " again: killing everything now");
        killAll(now);
      }
    }
  }
}

void Supervisor::readOutput(bool until_end) {
  for (auto it = streams_.begin(); it != streams_.end();) {
    if (readStream(*it, until_end)) {
      ++it;
    } else {
      close(it->fd);
      it = streams_.erase(it);
    }
  }
}

bool Supervisor::readStream(OutputStream& stream, bool until_end) {
  static char buf[kReadChunk];
  for (int chunk = 0; until_end || chunk < kMaxChunksPerWakeup; ++chunk) {
    const ssize_t n = read(stream.fd, buf, sizeof(buf));
    if (n > 0) {
      for (const auto& line : stream.splitter.feed(buf, static_cast<size_t>(n))) emitLine(stream.name, line);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) return true;
    for (const auto& line : stream.splitter.finish()) emitLine(stream.name, line);
    return false;
  }
  return true;
}

void Supervisor::emitLine(const std::string& name, const std::string& text) {
  console_.line(name, text);
  logs_.write(name, text);
}

void Supervisor::reapChildren(LaunchClock::time_point now) {
  int status = 0;
  pid_t pid;
  // As a child subreaper the launcher also reaps orphaned descendants here; only leaders matter.
  while ((pid = waitpid(-1, &status, WNOHANG)) > 0)
    if (const auto i = table_.indexOfPid(pid)) onExit(*i, ExitStatus::fromWaitStatus(status), now);
}

void Supervisor::onExit(size_t i, ExitStatus status, LaunchClock::time_point now) {
  const int pgid = table_[i].pid;
  const bool was_stopping = table_[i].state == RunState::Stopping;
  const RunState next = table_.exited(i, status, now);
  const ProcessRecord& r = table_[i];
  if (!was_stopping && processGroupExists(pgid)) {
    // Whatever the process left behind in its group goes with it, before any restart.
    kill(-pgid, SIGKILL);
    ending_[pgid] = {r.spec.name, now, true};
  }
  std::string what = r.spec.name + " ended: " + status.describe();
  if (next == RunState::Restarting)
    what += "; restarting in " + seconds(std::chrono::duration<double>(r.next_start - now).count());
  else if (next == RunState::Crashed)
    what += shutting_down_ ? "" : " (auto_respawn is off: not restarted)";
  event(what);
  logs_.write(r.spec.name, "[launch] " + what);
  publish(i);
  if (r.spec.required && next != RunState::Restarting && !shutting_down_) {
    event(r.spec.name + " is required: stopping everything");
    required_failed_ = !status.clean();
    beginShutdown(now);
  }
}

void Supervisor::beginShutdown(LaunchClock::time_point now) {
  shutting_down_ = true;
  table_.cancelPendingStarts();
  stopNextLevel(now);
}

// Called again whenever every group asked to stop is gone: the stop order is the reverse of the
// start order, so consumers that started first (a recorder, the mapping) still receive what the
// stages above them publish while they finish.
void Supervisor::stopNextLevel(LaunchClock::time_point now) {
  const std::vector<size_t> level = table_.nextToStop();
  if (level.empty()) return;
  std::string names;
  for (size_t i : level) names += " " + table_[i].spec.name;
  event("stopping start_order " + std::to_string(table_[level.front()].spec.start_order) + ":" + names);
  for (size_t i : level) signalToStop(i, table_[i].spec.stop_signal, now);
}

void Supervisor::signalToStop(size_t i, int sig, LaunchClock::time_point now) {
  const int pgid = table_[i].pid;
  signalGroup(pgid, sig);  // the whole group: children of children stop too
  table_.stopping(i, now);
  ending_[pgid] = {table_[i].spec.name, table_[i].kill_deadline, sig == SIGKILL};
  publish(i);
}

void Supervisor::killAll(LaunchClock::time_point now) {
  for (auto& [pgid, group] : ending_) {
    signalGroup(pgid, SIGKILL);
    group.killed = true;
  }
  for (size_t i : table_.running()) signalToStop(i, SIGKILL, now);  // the levels still waiting their turn
}

void Supervisor::enforceDeadlines(LaunchClock::time_point now) {
  for (auto it = ending_.begin(); it != ending_.end();) {
    auto& [pgid, group] = *it;
    const bool leader_running = table_.indexOfPid(pgid).has_value();
    if (!leader_running && !processGroupExists(pgid)) {
      it = ending_.erase(it);
      continue;
    }
    if (!group.killed && now >= group.deadline) {
      event(group.name + " did not stop in time: SIGKILL");
      signalGroup(pgid, SIGKILL);
      group.killed = true;
    }
    ++it;
  }
}

void Supervisor::killStrayDescendants() {
  // Processes that left their process group (setsid, daemons) were re-parented to the launcher,
  // a child subreaper: whatever still has the launcher as parent now is a leftover.
  // Killing one may re-parent its own children to the launcher: repeat until none is left.
  for (int round = 0; round < 100; ++round) {
    std::vector<int> killed;
    for (const auto& p : listProcesses())
      if (p.ppid == getpid() && kill(p.pid, SIGKILL) == 0) killed.push_back(p.pid);
    for (int pid : killed) waitpid(pid, nullptr, 0);
    if (killed.empty()) return;
    event("killed " + std::to_string(killed.size()) + " leftover descendant process(es)");
  }
}

void Supervisor::sampleUsage(LaunchClock::time_point now) {
  const auto groups = usageByProcessGroup(listProcesses());
  const double page_mb = static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
  for (size_t i = 0; i < table_.size(); ++i) {
    const ProcessRecord& r = table_[i];
    const auto g = groups.find(r.pid);
    if (r.pid <= 0 || g == groups.end()) continue;
    UsageSample& prev = usage_[i];
    const double cpu = prev.pid == r.pid ? cpuPercent(prev.ticks, g->second.cpu_ticks,
                                                      std::chrono::duration<double>(now - prev.at).count(),
                                                      sysconf(_SC_CLK_TCK))
                                         : 0.0;
    prev = {r.pid, g->second.cpu_ticks, now};
    table_.setUsage(i, cpu, static_cast<double>(g->second.rss_pages) * page_mb);
  }
}

void Supervisor::publish(size_t i) { status_.publish(table_[i]); }

void Supervisor::publishAll() {
  for (size_t i = 0; i < table_.size(); ++i) publish(i);
}

void Supervisor::event(const std::string& text) {
  console_.line("launch", text);
  logs_.write("launcher", text);
}

}  // namespace polarslam
