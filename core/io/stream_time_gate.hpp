#pragma once
// A plausibility gate on the time stamps of input streams (laser, sonar, odometry, ground truth,
// ...). One message stamped far from the others — an hour in the future, say — must not become
// the new clock: every later message would then look late ("time went backwards"), and the
// estimators would predict across the hour. The gate keeps one clock for all streams (the latest
// accepted stamp) and rejects a stamp further than max_jump from it. A real change of clock (a
// log that resumes after a pause, a sensor restarted with another time base) is adopted once
// one stream has sent `confirmations` consecutive messages consistent with the new time.
#include <cstdint>
#include <map>
#include <string>

namespace polarslam {

struct StreamTimeGateConfig {
  int64_t max_jump_us = 10'000'000;  ///< a stamp further than this from the clock is a jump
  int confirmations = 3;             ///< consecutive consistent messages that adopt a jump
};

class StreamTimeGate {
 public:
  explicit StreamTimeGate(StreamTimeGateConfig config = {}) : config_(config) {}

  /// Empty when `utime` on `stream` is plausible (and then part of the clock); otherwise the
  /// reason the message is rejected. A stamp earlier than the stream's previous one is not
  /// judged here: ordering is the consumer's business.
  std::string admit(const std::string& stream, int64_t utime);

  bool started() const { return clock_ != kUnset; }
  int64_t clock() const { return clock_; }
  long rejected() const { return rejected_; }
  long adoptedJumps() const { return adopted_jumps_; }

 private:
  static constexpr int64_t kUnset = INT64_MIN;
  struct Pending {
    int64_t last = kUnset;
    int count = 0;
  };
  bool nearClock(int64_t utime) const;
  bool continuesPending(const Pending& pending, int64_t utime) const;

  StreamTimeGateConfig config_;
  int64_t clock_ = kUnset;
  std::map<std::string, Pending> pending_;
  long rejected_ = 0, adopted_jumps_ = 0;
};

}  // namespace polarslam
