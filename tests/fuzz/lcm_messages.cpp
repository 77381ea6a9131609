// libFuzzer target: every LCM message a process consumes, handled as processes/common does it:
// decodeLcm() (the generated decode(), exceptions = a rejected message) on arbitrary bytes, then the
// validating fromLcm() of processes/common/lcm_convert. The first input byte picks the type.
#include <cstdint>
#include <string>

#include "common/lcm_convert.hpp"
#include "common/lcm_decode.hpp"
#include "fuzz_support.hpp"

namespace {

template <typename MsgT, typename CoreT>
void decodeAndConvert(const uint8_t* data, size_t size) {
  MsgT msg;
  if (!polarslam::decodeLcm(msg, data, size)) return;
  CoreT out;
  const std::string error = polarslam::fromLcm(msg, out);
  (void)error;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t kind = data[0] % 6;
  ++data;
  --size;
  switch (kind) {
    case 0: decodeAndConvert<polarslam::laser_scan_t, polarslam::LaserScan>(data, size); break;
    case 1: decodeAndConvert<polarslam::odometry_t, polarslam::OdometryReading>(data, size); break;
    case 2: decodeAndConvert<polarslam::sonar_targets_t, polarslam::SonarScan>(data, size); break;
    case 3: decodeAndConvert<polarslam::pose_t, polarslam::PoseStamped>(data, size); break;
    case 4: decodeAndConvert<polarslam::features_t, polarslam::FeatureSet>(data, size); break;
    default: decodeAndConvert<polarslam::grid_map_t, polarslam::GridSlice>(data, size); break;
  }
  return 0;
}
