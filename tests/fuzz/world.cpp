// libFuzzer target: the world YAML loader (core/sim/world_file), read from a temporary file.
#include <stdexcept>

#include "fuzz_support.hpp"
#include "sim/world.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static polarslam::fuzz::TempFile file(".yaml");
  try {
    (void)polarslam::loadWorld(file.write(data, size));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
