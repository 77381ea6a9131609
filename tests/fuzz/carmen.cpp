// libFuzzer target: the CARMEN log reader (core/io/carmen). Malformed lines must be counted,
// never fatal; every event it keeps must be finite and consistent with its beam count.
#include <sstream>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "io/carmen.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(polarslam::fuzz::asText(data, size)));
  const polarslam::CarmenLog log = polarslam::readCarmenLog(in);
  if (log.malformed_count < static_cast<int64_t>(log.malformed.size())) throw std::logic_error("malformed count");
  for (const auto& event : log.events) {
    if (event.line < 1 || event.line > log.lines) throw std::logic_error("event line out of range");
    if (event.isLaser() && event.laser().ranges.empty()) throw std::logic_error("laser event without beams");
  }
  return 0;
}
