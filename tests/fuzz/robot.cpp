// libFuzzer target: the robot (simulator config) YAML loader (core/sim/sim_config).
#include <stdexcept>

#include "fuzz_support.hpp"
#include "sim/sim_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static polarslam::fuzz::TempFile file(".yaml");
  try {
    (void)polarslam::loadSimConfig(file.write(data, size));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
