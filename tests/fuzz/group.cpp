// libFuzzer target: the launcher's group file loader (core/launch/group_file), then command
// selection over whatever it accepted.
#include <stdexcept>

#include "fuzz_support.hpp"
#include "launch/group_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static polarslam::fuzz::TempFile file(".yaml");
  static const polarslam::Environment env{{"HOME", "/home/fuzz"}, {"PATH", "/usr/bin:/bin"}};
  try {
    const auto root = polarslam::loadGroupFile(file.write(data, size), env);
    (void)polarslam::selectCommands(root, "", "");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
