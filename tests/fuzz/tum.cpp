// libFuzzer target: the TUM trajectory reader (core/io/tum), then a format/parse round trip of
// whatever it accepted.
#include <stdexcept>

#include "fuzz_support.hpp"
#include "io/tum.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto poses = polarslam::parseTumTrajectory(polarslam::fuzz::asText(data, size), "fuzz.tum");
    (void)polarslam::parseTumTrajectory(polarslam::formatTumTrajectory(poses), "fuzz-roundtrip.tum");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
