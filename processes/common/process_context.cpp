#include "common/process_context.hpp"

#include <algorithm>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "polarslam/process_status_t.hpp"

namespace polarslam {
namespace {

std::atomic<bool> g_stop{false};
// After a stop, input already queued is still handled: until nothing has come for kDrainQuiet,
// but for kDrainLimit at most, so that a peer that keeps publishing cannot hold up the exit.
constexpr int kDrainQuietMs = 50;
constexpr auto kDrainLimit = std::chrono::seconds(2);
void onSignal(int) { g_stop = true; }

double residentMegabytes() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

}  // namespace

std::string hostName() {
  char buf[256] = {0};
  gethostname(buf, sizeof(buf) - 1);
  return buf;
}

int64_t nowUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool SequenceTracker::accept(const std::string& channel, int64_t seq) {
  auto it = last_.find(channel);
  if (it == last_.end()) {
    last_[channel] = seq;
    return true;
  }
  if (seq < it->second && (seq <= 1 || it->second - seq > kRestartJump)) {
    ++restarts_;
    it->second = seq;
    return true;
  }
  if (seq <= it->second) return false;
  dropped_ += seq - it->second - 1;
  it->second = seq;
  return true;
}

std::string resolveLcmUrl(const std::string& option) {
  if (!option.empty()) return option;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
}

ProcessContext::ProcessContext(std::string name, const std::string& lcm_url)
    : name_(std::move(name)), lcm_(std::make_unique<lcm::LCM>(resolveLcmUrl(lcm_url))) {
  if (!lcm_->good())
    throw std::runtime_error("cannot open LCM at '" + resolveLcmUrl(lcm_url) +
                             "' (no multicast route? try: ip route add 224.0.0.0/4 dev lo)");
}

ProcessContext::ProcessContext(std::string name, const ProcessOptions& options)
    : ProcessContext(std::move(name), options.lcm_url) {
  time_gate_ = StreamTimeGate({static_cast<int64_t>(options.max_time_jump_s * 1e6), 3});
}

void addProcessOptions(CLI::App& app, ProcessOptions& options) {
  app.add_option("--lcm-url", options.lcm_url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  app.add_option("--max-time-jump", options.max_time_jump_s,
                 "s: input stamped further than this from the other input is rejected and counted, "
                 "not adopted as the clock")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

void ProcessContext::reject(const std::string& kind) {
  ++rejected_;
  if (reject_kinds_[kind]++ == 0) std::cerr << "[" << name_ << "] rejected: " << kind << " (further ones counted in PROCESS_STATUS)\n";
}

bool ProcessContext::checkSequence(const std::string& channel, int64_t seq) {
  if (sequences_.accept(channel, seq)) return true;
  reject(channel + ": duplicate or out-of-order sequence number");
  return false;
}

void ProcessContext::publishStatus(const std::string& state) {
  polarslam::process_status_t msg;
  msg.utime = nowUtime();
  msg.name = name_;
  msg.host = hostName();
  msg.pid = static_cast<int32_t>(getpid());
  msg.state = state;
  msg.restarts = 0;
  msg.messages_handled = handled_;
  msg.messages_rejected = rejected_;
  msg.messages_dropped = sequences_.dropped();
  for (const auto& [kind, count] : reject_kinds_) {
    msg.reject_kinds.push_back(kind);
    msg.reject_counts.push_back(count);
  }
  msg.num_reject_kinds = static_cast<int32_t>(msg.reject_kinds.size());
  msg.cpu_percent = 0.0;
  msg.rss_mb = residentMegabytes();
  lcm_->publish("PROCESS_STATUS", &msg);
}

void ProcessContext::installSignalHandlers() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

bool ProcessContext::stopRequested() { return g_stop.load(); }

void ProcessContext::enableJournal(const JournalOptions& options) {
  if (options.path.empty()) return;
  journal_ = std::make_unique<InputJournal>(
      options.path, std::chrono::milliseconds(static_cast<int64_t>(options.flush_period * 1000.0)));
}

void ProcessContext::resumeFromSnapshot(uint64_t generation, size_t covered) {
  snapshot_generation_ = generation;
  snapshot_covers_ = covered;
}

void ProcessContext::resumeFromJournal() {
  std::vector<LogEvent> events = journal_->readEvents();
  if (!journal_->refused().empty()) std::cerr << "[" << name_ << "] warning: " << journal_->refused() << "\n";
  uint64_t generation = journal_->generation();
  if (snapshot_generation_ == generation + 1) {
    // The snapshot was written but the journal not yet cut: skip what the snapshot holds.
    events.erase(events.begin(), events.begin() + static_cast<long>(std::min(snapshot_covers_, events.size())));
    generation = snapshot_generation_;
  } else if (snapshot_generation_ != generation) {
    std::cerr << "[" << name_ << "] warning: journal " << journal_->path() << " follows snapshot " << generation
              << ", the state restored is snapshot " << snapshot_generation_ << ": replaying the journal as it is\n";
    generation = std::max(generation, snapshot_generation_);
  }
  journal_->rewrite(generation, events);
  if (events.empty()) return;
  replaying_ = true;
  for (const LogEvent& event : events) {
    lcm::ReceiveBuffer buffer{const_cast<uint8_t*>(event.data.data()), static_cast<uint32_t>(event.data.size()),
                              event.utime};
    for (const auto& sub : subscriptions_)
      if (sub->channel == event.channel) sub->raw(&buffer);
  }
  replaying_ = false;
  std::cerr << "[" << name_ << "] resumed from journal " << journal_->path() << ": " << events.size()
            << " messages replayed\n";
}

void ProcessContext::run(std::function<bool()> done, std::function<void()> tick,
                         std::chrono::milliseconds tick_period) {
  installSignalHandlers();
  if (journal_) resumeFromJournal();
  publishStatus("running");
  auto next_tick = std::chrono::steady_clock::now() + tick_period;
  auto next_status = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (!g_stop && !(done && done())) {
    if (lcm_->handleTimeout(50) < 0) {
      if (g_stop) break;  // the stop signal interrupted the wait
      std::cerr << "[" << name_ << "] LCM receive error\n";
      break;
    }
    if (journal_) journal_->flushIfDue();
    const auto now = std::chrono::steady_clock::now();
    if (tick && now >= next_tick) {
      tick();
      next_tick = now + tick_period;
    }
    if (now >= next_status) {
      publishStatus("running");
      next_status = now + std::chrono::seconds(1);
    }
  }
  drainQueuedInput();
  publishStatus("stopped");
}

// Stages stop in reverse start order (polarslam-launch): when one is told to stop, those feeding
// it have already exited, and their last messages wait in its queue. Handled before the exit
// work, they reach the final outputs.
void ProcessContext::drainQueuedInput() {
  const auto give_up = std::chrono::steady_clock::now() + kDrainLimit;
  while (std::chrono::steady_clock::now() < give_up) {
    errno = 0;
    const int result = lcm_->handleTimeout(kDrainQuietMs);
    if (result == 0) break;                   // quiet: nothing more was queued
    if (result < 0 && errno != EINTR) break;  // a receive error, not just another signal
  }
  if (journal_) journal_->flushIfDue();
}

}  // namespace polarslam
