#include "io/stream_time_gate.hpp"

#include <algorithm>

namespace polarslam {

namespace {

/// |a - b| without overflow, for any two int64 stamps (corrupt ones near the ends included).
uint64_t distance(int64_t a, int64_t b) {
  return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b) : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

}  // namespace

bool StreamTimeGate::nearClock(int64_t utime) const {
  return distance(utime, clock_) <= static_cast<uint64_t>(config_.max_jump_us);
}

bool StreamTimeGate::continuesPending(const Pending& pending, int64_t utime) const {
  return pending.count > 0 && utime >= pending.last && distance(utime, pending.last) <= static_cast<uint64_t>(config_.max_jump_us);
}

std::string StreamTimeGate::admit(const std::string& stream, int64_t utime) {
  Pending& pending = pending_[stream];
  if (clock_ == kUnset || nearClock(utime)) {
    pending = {};
    clock_ = clock_ == kUnset ? utime : std::max(clock_, utime);
    return {};
  }
  pending = continuesPending(pending, utime) ? Pending{utime, pending.count + 1} : Pending{utime, 1};
  if (pending.count >= config_.confirmations) {
    clock_ = utime;
    pending = {};
    ++adopted_jumps_;
    return {};
  }
  ++rejected_;
  return stream + ": time stamp jumps more than " + std::to_string(config_.max_jump_us / 1000000) +
         " s from the other input (not adopted as the clock)";
}

}  // namespace polarslam
