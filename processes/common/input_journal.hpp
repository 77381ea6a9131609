#pragma once
// Crash recovery for the stateful processes (the SLAM estimators, the grid): every input message
// is appended to a journal, an ordinary LCM log, handed to the kernel after every message (or every
// flush period), so a kill -9 loses none of it. A process
// restarted after a crash (kill -9, a bug) replays the journal through its own handlers before it
// listens again, so it resumes with the state it had — the same state, because the core is
// deterministic — and a final map still covers the whole run. Messages that arrived while it
// was down are the only loss.
//
// A journal belongs to one launch: its first event (channel POLARSLAM_JOURNAL) names the launch
// that wrote it, POLARSLAM_LAUNCH_ID as polarslam-launch sets it (empty for a process started by
// hand). A journal of another launch (a reused --run-dir) is stale: it is refused, kept aside as
// FILE.stale, and the process starts empty, saying so on stderr.
//
// A process that takes snapshots of its state (polarslam-psm-slam --snapshot-period) cuts its
// journal after each one: the journal then holds only the messages since, and its header counts
// the cuts (the generation), so that a restart can tell which snapshot the journal continues.
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/lcm_log.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

class InputJournal {
 public:
  /// `launch_id`: who this process belongs to (default: the POLARSLAM_LAUNCH_ID environment variable).
  InputJournal(std::string path, std::chrono::milliseconds flush_period, std::string launch_id = currentLaunchId());
  InputJournal(const InputJournal&) = delete;
  InputJournal& operator=(const InputJournal&) = delete;

  static std::string currentLaunchId();
  static constexpr const char* kHeaderChannel = "POLARSLAM_JOURNAL";

  /// The journal's intact events (a last event torn by a crash is dropped; nothing from a stale journal). Rewrites the file
  /// with exactly those (temp file + rename, so a crash now loses nothing) and keeps it open for
  /// appending. Call once, before append().
  std::vector<LogEvent> recover();
  /// recover() in two steps: the intact events (generation() tells whose cut they follow), then
  /// the journal rewritten as `generation` holding `events` and kept open for appending.
  std::vector<LogEvent> readEvents();
  void rewrite(uint64_t generation, const std::vector<LogEvent>& events);
  /// After a snapshot: the journal starts over, empty, as `generation`.
  void cut(uint64_t generation) { rewrite(generation, {}); }
  /// Cuts so far (0: never cut); events appended since the last cut.
  uint64_t generation() const { return generation_; }
  size_t events() const { return events_; }
  void append(const std::string& channel, int64_t utime, const void* data, size_t size);
  /// Flushes to the kernel when the flush period has passed since the last flush (always when it is 0).
  void flushIfDue();
  const std::string& path() const { return path_; }
  /// Why the journal found on disk was not replayed ("" when it was, or there was none).
  const std::string& refused() const { return refused_; }

 private:
  std::string path_, launch_id_, refused_;
  uint64_t generation_ = 0;
  size_t events_ = 0;
  std::chrono::milliseconds flush_period_;
  std::unique_ptr<lcm::LogFile> log_;
  std::chrono::steady_clock::time_point last_flush_;
};

struct JournalOptions {
  std::string path;         ///< empty: no journal
  double flush_period = 0.0;  ///< s; 0: after every message (one write(2) each, a few hundred a second)
};

/// --journal FILE and --journal-flush S, the same on every process that keeps state.
void addJournalOptions(CLI::App& app, JournalOptions& options);

}  // namespace polarslam
