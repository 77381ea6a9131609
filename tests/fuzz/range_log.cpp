// libFuzzer target: the range-log readers behind `polarslam import` (core/io/range_log and the
// CMU, Duke and Mines readers), with format detection. Text that is no log may throw
// std::runtime_error (a clear error naming the input); anything else that escapes, or an event
// inconsistent with the log, is a finding.
#include <cmath>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "io/range_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(polarslam::fuzz::asText(data, size));
  polarslam::RangeLog log;
  try {
    log = polarslam::readRangeLogText(text, "fuzz-input", polarslam::RangeLogFormat::Auto);
  } catch (const std::runtime_error&) {
    return 0;
  }
  if (log.malformed_count < static_cast<int64_t>(log.malformed.size())) throw std::logic_error("malformed count");
  for (const auto& event : log.events) {
    if (event.line < 1 || event.line > log.lines) throw std::logic_error("event line out of range");
    if (!event.isLaser()) continue;
    const auto& scan = event.laser();
    if (scan.ranges.empty()) throw std::logic_error("laser event without beams");
    if (!std::isfinite(scan.angle_min) || !(scan.angle_increment > 0.0)) throw std::logic_error("bad beam geometry");
  }
  return 0;
}
