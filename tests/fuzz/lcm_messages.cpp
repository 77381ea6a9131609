// libFuzzer target: every LCM message type a process or a log reader decodes, handled as
// processes/common does it: decodeLcm() (layout check, then the generated decode(); exceptions = a
// rejected message) on arbitrary bytes, then the validating fromLcm() of processes/common/lcm_convert
// where the type has one. The first input byte picks the type.
#include <cstdint>
#include <string>

#include "common/lcm_convert.hpp"
#include "common/lcm_decode.hpp"
#include "fuzz_support.hpp"

namespace {

template <typename MsgT>
void decodeOnly(const uint8_t* data, size_t size) {
  MsgT msg;
  (void)polarslam::decodeLcm(msg, data, size);
}

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
  using namespace polarslam;
  if (size < 1) return 0;
  const uint8_t kind = data[0] % 17;
  ++data;
  --size;
  switch (kind) {
    case 0: decodeAndConvert<laser_scan_t, LaserScan>(data, size); break;
    case 1: decodeAndConvert<odometry_t, OdometryReading>(data, size); break;
    case 2: decodeAndConvert<sonar_targets_t, SonarScan>(data, size); break;
    case 3: decodeAndConvert<pose_t, PoseStamped>(data, size); break;
    case 4: decodeAndConvert<features_t, FeatureSet>(data, size); break;
    case 5: decodeAndConvert<grid_map_t, GridSlice>(data, size); break;
    case 6: decodeAndConvert<slam_map_t, FeatureMap>(data, size); break;
    case 7: decodeAndConvert<scan_anchors_t, ScanAnchors>(data, size); break;
    case 8: decodeOnly<path_t>(data, size); break;
    case 9: decodeOnly<pose_graph_t>(data, size); break;
    case 10: decodeOnly<process_status_t>(data, size); break;
    case 11: decodeOnly<scan_match_t>(data, size); break;
    case 12: decodeOnly<grid_request_t>(data, size); break;
    case 13: decodeOnly<grid_status_t>(data, size); break;
    case 14: decodeOnly<anchored_pose_t>(data, size); break;
    case 15: decodeOnly<goal_t>(data, size); break;
    default: decodeOnly<map_request_t>(data, size); break;
  }
  return 0;
}
