// libFuzzer target: the JSON line reader of `polarslam match` (processes/common/match_request);
// every scan it accepts must also pass validateScan.
#include <cstdlib>
#include <string>

#include "common/match_request.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  polarslam::MatchRequest request;
  const std::string why = polarslam::parseMatchRequest(std::string(polarslam::fuzz::asText(data, size)), request);
  if (why.empty() && (!polarslam::validateScan(request.ref).empty() || !polarslam::validateScan(request.cur).empty()))
    std::abort();
  return 0;
}
