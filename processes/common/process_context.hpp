#pragma once
// Scaffolding shared by every polarslam process: LCM connection, typed subscriptions that
// count undecodable messages, rejection counters logged once per kind, sequence-gap counting,
// PROCESS_STATUS publishing and a signal-aware main loop.
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/input_journal.hpp"
#include "common/lcm_convert.hpp"
#include "common/lcm_decode.hpp"
#include "io/stream_time_gate.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace polarslam {

int64_t nowUtime();
/// This machine's name, as PROCESS_STATUS carries it.
std::string hostName();

/// Counts per-channel sequence gaps and repeats. Returns false for a duplicate or stale message.
/// A sequence number that starts over (0 or 1, or far below the last one) is a restarted
/// publisher, not a stale message: it is accepted and counted in restarts().
class SequenceTracker {
 public:
  static constexpr int64_t kRestartJump = 100;  ///< further back than this is a restart

  bool accept(const std::string& channel, int64_t seq);
  int64_t dropped() const { return dropped_; }
  int64_t restarts() const { return restarts_; }

 private:
  std::map<std::string, int64_t> last_;
  int64_t dropped_ = 0, restarts_ = 0;
};

/// What every processing stage is told on its command line (addProcessOptions).
struct ProcessOptions {
  std::string lcm_url;
  /// Input stamped further than this from the other input is rejected (io/stream_time_gate.hpp).
  double max_time_jump_s = 10.0;
};
void addProcessOptions(CLI::App& app, ProcessOptions& options);

/// Whether a subscription's messages carry stream time (sensor data and what is computed from it,
/// gated by the StreamTimeGate) or wall-clock time (requests, goals, status).
enum class Stamps { WallClock, StreamTime };

class ProcessContext {
 public:
  ProcessContext(std::string name, const std::string& lcm_url);
  ProcessContext(std::string name, const ProcessOptions& options);
  ProcessContext(const ProcessContext&) = delete;
  ProcessContext& operator=(const ProcessContext&) = delete;

  lcm::LCM& lcm() { return *lcm_; }
  const std::string& name() const { return name_; }

  /// Subscribes with a typed handler; messages that do not decode as MsgT, and stream-time
  /// messages whose stamp jumps away from the other input, are rejected and counted. Only what
  /// passes goes into the journal, so that a restart does not replay a rejected message.
  template <typename MsgT>
  void subscribe(const std::string& channel, std::function<void(const MsgT&)> handler,
                 Stamps stamps = Stamps::WallClock) {
    auto sub = std::make_unique<Subscription>();
    sub->context = this;
    sub->raw = [this, handler, channel, stamps](const lcm::ReceiveBuffer* rbuf) {
      MsgT msg;
      if (!decodeLcm(msg, rbuf->data, rbuf->data_size)) {
        reject(channel + ": message does not decode as " + MsgT::getTypeName());
        return;
      }
      if (stamps == Stamps::StreamTime) {
        // Sequence first: a message the time gate rejects is counted rejected, not also as a gap.
        if constexpr (requires { msg.seq; })
          if (!checkSequence(channel, msg.seq)) return;
        if (const std::string why = time_gate_.admit(channel, msg.utime); !why.empty()) return reject(why);
      }
      if (journal_ && !replaying_) journal_->append(channel, rbuf->recv_utime, rbuf->data, rbuf->data_size);
      handler(msg);
    };
    lcm::Subscription* s = lcm_->subscribe(channel, &Subscription::onMessage, sub.get());
    s->setQueueCapacity(1000);
    sub->channel = channel;
    subscriptions_.push_back(std::move(sub));
  }

  /// The usual input path for stream data: decode as MsgT, check its sequence number, gate its time
  /// stamp, convert to the core type ValueT (a conversion that fails is rejected with its reason),
  /// then call `handler`, which counts the message handled (or rejects it) itself.
  template <typename MsgT, typename ValueT>
  void subscribeConverted(const std::string& channel, std::function<void(ValueT&)> handler) {
    subscribe<MsgT>(
        channel,
        [this, channel, handler](const MsgT& msg) {
          ValueT value;
          if (const std::string why = fromLcm(msg, value); !why.empty()) return reject(why);
          handler(value);
        },
        Stamps::StreamTime);
  }

  /// Nothing is published while the journal is replayed: those messages went out before.
  template <typename MsgT>
  void publish(const std::string& channel, const MsgT& msg) {
    if (!replaying_) lcm_->publish(channel, &msg);
  }

  /// Crash recovery (input_journal.hpp): run() first replays the journal, then appends to it.
  void enableJournal(const JournalOptions& options);
  bool journaling() const { return journal_ != nullptr; }
  /// With snapshots: the process has restored itself from the snapshot of `generation` (0: none),
  /// which covers `covered` messages of the journal as it was before that snapshot cut it (a crash
  /// between writing a snapshot and cutting the journal). Call before run().
  void resumeFromSnapshot(uint64_t generation, size_t covered);
  /// A snapshot of the state after every message so far is safely written: the journal starts over.
  void cutJournal() { journal_->cut(journal_->generation() + 1); }
  uint64_t journalGeneration() const { return journal_ ? journal_->generation() : 0; }
  size_t journalEvents() const { return journal_ ? journal_->events() : 0; }
  /// True while run() replays the journal.
  bool replaying() const { return replaying_; }

  void handled() { ++handled_; }
  /// Counts a rejected message; the first of each kind is logged to stderr.
  void reject(const std::string& kind);
  /// Sequence check for an input message; counts gaps as drops, rejects duplicates.
  bool checkSequence(const std::string& channel, int64_t seq);

  int64_t handledCount() const { return handled_; }
  int64_t rejectedCount() const { return rejected_; }
  const std::map<std::string, int64_t>& rejectKinds() const { return reject_kinds_; }

  void publishStatus(const std::string& state);
  /// Runs until SIGINT/SIGTERM or until `done()` returns true; calls `tick` about every period.
  /// Then handles the input already queued (a couple of seconds at most) and returns, so that
  /// the caller's exit work (final map, final graph) includes it.
  void run(std::function<bool()> done = {}, std::function<void()> tick = {},
           std::chrono::milliseconds tick_period = std::chrono::milliseconds(1000));
  static bool stopRequested();
  static void installSignalHandlers();

 private:
  void resumeFromJournal();
  void drainQueuedInput();

  struct Subscription {
    ProcessContext* context = nullptr;
    std::string channel;
    std::function<void(const lcm::ReceiveBuffer*)> raw;
    void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string&) { raw(rbuf); }
  };

  std::string name_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  int64_t handled_ = 0, rejected_ = 0;
  std::map<std::string, int64_t> reject_kinds_;
  SequenceTracker sequences_;
  StreamTimeGate time_gate_;
  std::unique_ptr<InputJournal> journal_;
  bool replaying_ = false;
  uint64_t snapshot_generation_ = 0;
  size_t snapshot_covers_ = 0;
};

/// Resolves the LCM URL: explicit option, then LCM_DEFAULT_URL, then multicast with TTL 0.
std::string resolveLcmUrl(const std::string& option);

}  // namespace polarslam
