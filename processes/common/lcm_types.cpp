#include "common/lcm_types.hpp"

#include <array>
#include <utility>

#include "polarslam/features_t.hpp"
#include "polarslam/goal_t.hpp"
#include "polarslam/grid_map_t.hpp"
#include "polarslam/grid_request_t.hpp"
#include "polarslam/grid_status_t.hpp"
#include "polarslam/laser_scan_t.hpp"
#include "polarslam/map_request_t.hpp"
#include "polarslam/odometry_t.hpp"
#include "polarslam/path_t.hpp"
#include "polarslam/pose_graph_t.hpp"
#include "polarslam/pose_t.hpp"
#include "polarslam/process_status_t.hpp"
#include "polarslam/scan_anchors_t.hpp"
#include "polarslam/scan_match_t.hpp"
#include "polarslam/slam_map_t.hpp"
#include "polarslam/sonar_targets_t.hpp"

namespace polarslam {
namespace {

template <typename T>
std::pair<int64_t, const char*> entry() { return {T::getHash(), T::getTypeName()}; }

}  // namespace

std::string lcmTypeName(const uint8_t* data, size_t size) {
  static const std::array known = {
      entry<laser_scan_t>(), entry<sonar_targets_t>(), entry<odometry_t>(), entry<pose_t>(),
      entry<features_t>(),   entry<slam_map_t>(),      entry<scan_anchors_t>(), entry<scan_match_t>(),
      entry<process_status_t>(), entry<goal_t>(),     entry<grid_request_t>(),
      entry<path_t>(),       entry<grid_status_t>(),   entry<pose_graph_t>(), entry<grid_map_t>(),
      entry<map_request_t>()};
  if (size < 8) return {};
  int64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = static_cast<int64_t>((static_cast<uint64_t>(hash) << 8) | data[i]);
  for (const auto& [h, name] : known)
    if (h == hash) return std::string("polarslam.") + name;
  return {};
}

}  // namespace polarslam
