#include "launch/process_table.hpp"

#include <sys/wait.h>

#include <algorithm>

namespace polarslam {
namespace {

LaunchClock::duration seconds(double s) {
  return std::chrono::duration_cast<LaunchClock::duration>(std::chrono::duration<double>(s));
}

bool isPending(RunState s) { return s == RunState::Scheduled || s == RunState::Restarting; }

}  // namespace

std::string stateName(RunState state) {
  switch (state) {
    case RunState::Scheduled: return "starting";
    case RunState::Running: return "running";
    case RunState::Restarting: return "restarting";
    case RunState::Stopping: return "stopping";
    case RunState::Stopped: return "stopped";
    case RunState::Crashed: return "crashed";
    case RunState::Failed: return "failed";
  }
  return "unknown";
}

ExitStatus ExitStatus::fromWaitStatus(int wait_status) {
  if (WIFSIGNALED(wait_status)) return {true, WTERMSIG(wait_status)};
  return {false, WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : 0};
}

std::string ExitStatus::describe() const {
  return signaled ? "killed by " + signalName(code) : "exit " + std::to_string(code);
}

ProcessTable::ProcessTable(std::vector<CommandSpec> commands, LaunchClock::time_point launch_time) {
  LaunchClock::time_point at = launch_time;
  for (auto& spec : commands) {
    at += seconds(spec.start_delay_s);
    ProcessRecord record;
    record.spec = std::move(spec);
    record.next_start = at;
    records_.push_back(std::move(record));
  }
}

std::optional<size_t> ProcessTable::indexOfPid(int pid) const {
  for (size_t i = 0; i < records_.size(); ++i)
    if (records_[i].pid == pid && pid > 0) return i;
  return std::nullopt;
}

bool ProcessTable::waiting(size_t i, LaunchClock::time_point now) const {
  const ProcessRecord& r = records_[i];
  return r.state == RunState::Scheduled && now < r.next_start + seconds(r.spec.wait_timeout_s) && !awaited(i).empty();
}

std::vector<size_t> ProcessTable::dueToStart(LaunchClock::time_point now) const {
  std::vector<size_t> due;
  for (size_t i = 0; i < records_.size(); ++i)
    if (isPending(records_[i].state) && records_[i].next_start <= now && !waiting(i, now)) due.push_back(i);
  return due;
}

std::optional<LaunchClock::time_point> ProcessTable::nextStart(LaunchClock::time_point now) const {
  std::optional<LaunchClock::time_point> earliest;
  for (size_t i = 0; i < records_.size(); ++i) {
    const ProcessRecord& r = records_[i];
    if (!isPending(r.state)) continue;
    // Past its delay and waiting for reports: the next time is its timeout (a report wakes the launcher).
    const auto at = r.next_start <= now && waiting(i, now) ? r.next_start + seconds(r.spec.wait_timeout_s) : r.next_start;
    if (!earliest || at < *earliest) earliest = at;
  }
  return earliest;
}

std::vector<std::string> ProcessTable::awaited(size_t i) const {
  std::vector<std::string> names;
  for (const std::string& name : records_[i].spec.wait_for)
    for (const ProcessRecord& r : records_)
      if (r.spec.name == name && !r.reported_running && (r.state == RunState::Running || isPending(r.state)))
        names.push_back(name);
  return names;
}

void ProcessTable::reportedRunning(size_t i) { records_[i].reported_running = true; }

void ProcessTable::started(size_t i, int pid, LaunchClock::time_point now) {
  ProcessRecord& r = records_[i];
  if (r.state == RunState::Restarting) ++r.restarts;
  r.state = RunState::Running;
  r.pid = pid;
  r.reported_running = false;
  r.started_at = now;
  r.cpu_percent = r.rss_mb = 0.0;
}

void ProcessTable::startFailed(size_t i, const std::string& error) {
  ProcessRecord& r = records_[i];
  r.state = RunState::Failed;
  r.pid = -1;
  r.error = error;
}

RunState ProcessTable::exited(size_t i, ExitStatus status, LaunchClock::time_point now) {
  ProcessRecord& r = records_[i];
  const bool stop_requested = r.state == RunState::Stopping;
  r.pid = -1;
  r.reported_running = false;
  r.last_exit = status.describe();
  r.cpu_percent = r.rss_mb = 0.0;
  if (stop_requested || status.clean()) {
    r.state = RunState::Stopped;
    return r.state;
  }
  if (!r.spec.auto_respawn || shutting_down_) {
    r.state = RunState::Crashed;
    return r.state;
  }
  const bool ran_long_enough = now - r.started_at >= seconds(r.spec.backoff.reset_after_s);
  r.consecutive_crashes = ran_long_enough ? 1 : r.consecutive_crashes + 1;
  r.state = RunState::Restarting;
  r.next_start = now + seconds(r.spec.backoff.delay(r.consecutive_crashes));
  return r.state;
}

void ProcessTable::stopping(size_t i, LaunchClock::time_point now) {
  ProcessRecord& r = records_[i];
  r.state = RunState::Stopping;
  r.kill_deadline = now + seconds(r.spec.stop_grace_s);
}

void ProcessTable::cancelPendingStarts() {
  shutting_down_ = true;
  for (auto& r : records_)
    if (r.state == RunState::Scheduled) r.state = RunState::Stopped;
    else if (r.state == RunState::Restarting) r.state = RunState::Crashed;
}

std::vector<size_t> ProcessTable::nextToStop() const {
  std::vector<size_t> next;
  for (size_t i : running()) {
    const int order = records_[i].spec.start_order;
    if (!next.empty() && order < records_[next.front()].spec.start_order) continue;
    if (!next.empty() && order > records_[next.front()].spec.start_order) next.clear();
    next.push_back(i);
  }
  return next;
}

std::vector<size_t> ProcessTable::running() const {
  std::vector<size_t> found;
  for (size_t i = 0; i < records_.size(); ++i)
    if (records_[i].state == RunState::Running) found.push_back(i);
  return found;
}

void ProcessTable::setUsage(size_t i, double cpu_percent, double rss_mb) {
  records_[i].cpu_percent = cpu_percent;
  records_[i].rss_mb = rss_mb;
}

bool ProcessTable::anyActive() const {
  return std::any_of(records_.begin(), records_.end(), [](const ProcessRecord& r) {
    return isPending(r.state) || r.state == RunState::Running || r.state == RunState::Stopping;
  });
}

bool ProcessTable::anyFailed() const {
  return std::any_of(records_.begin(), records_.end(), [](const ProcessRecord& r) {
    return r.state == RunState::Crashed || r.state == RunState::Failed;
  });
}

}  // namespace polarslam
