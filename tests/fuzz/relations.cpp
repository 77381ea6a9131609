// libFuzzer target: the Kümmerle relations parser (core/io/relations). Bad input must give a
// std::runtime_error; anything else (another exception, a crash, UB) is a finding.
#include <stdexcept>

#include "fuzz_support.hpp"
#include "io/relations.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto relations = polarslam::parseRelations(polarslam::fuzz::asText(data, size), "fuzz.relations");
    for (const auto& r : relations) (void)r.motion();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
