// libFuzzer target: the robot (simulator config) YAML loader (core/robot/robot_description).
#include <stdexcept>

#include "fuzz_support.hpp"
#include "robot/robot_description.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static polarslam::fuzz::TempFile file(".yaml");
  try {
    (void)polarslam::loadRobotDescription(file.write(data, size));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
