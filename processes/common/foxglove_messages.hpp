#pragma once
// polarslam data as foxglove.* JSON messages (schemas in foxglove_schemas.hpp). Frames: `map`,
// `odom`, `base_link`, `laser` (the robot base frame is `base` elsewhere in polarslam; Foxglove
// and ROS users expect `base_link`). Positions are 2D with z = 0, yaw as a quaternion about z.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "geometry/features.hpp"
#include "geometry/pose2.hpp"
#include "grid/grid_slice.hpp"
#include "laser/laser_scan.hpp"
#include "slam/feature_map.hpp"
#include "slam/pose_graph.hpp"

namespace polarslam::foxglove {

inline constexpr const char* kBaseFrame = "base_link";
inline constexpr const char* kLaserFrame = "laser";

/// {sec, nsec} of a µs time stamp (negative times clamp to 0: the schema's time is unsigned).
nlohmann::json timestamp(int64_t utime);
nlohmann::json pose(const Pose2& pose);
std::string base64(const std::string& bytes);

/// foxglove.Grid: one INT8 field "occupancy": −1 unknown, else P(occupied) in percent.
nlohmann::json grid(const GridSlice& slice, int64_t utime, const std::string& frame);
/// foxglove.LaserScan in the `laser` frame; beams without a return (NaN, ≥ range_max) have range 0.
nlohmann::json laserScan(const LaserScan& scan);
nlohmann::json poseInFrame(const PoseStamped& pose, const std::string& frame);
nlohmann::json posesInFrame(const std::vector<Pose2>& poses, int64_t utime, const std::string& frame);
nlohmann::json frameTransform(const Pose2& child_in_parent, int64_t utime, const std::string& parent,
                              const std::string& child);
/// foxglove.SceneUpdate of entity "slam_map" (frame map): line segments (blue), corners as two
/// 0.3 m arms along their walls (green), points as spheres (orange), and 95 % covariance
/// ellipses of corner and point positions plus, for lines, the 95 % band of d (dashed grey).
nlohmann::json featureMapScene(const FeatureMap& map);
/// foxglove.SceneUpdate of entity "pose_graph": nodes as spheres, odometry and match edges grey,
/// loop closures red (rejected ones faint).
nlohmann::json poseGraphScene(const PoseGraph& graph, int64_t utime);

/// The PROCESS_STATUS fields the built-in page and the foxglove.Log messages use.
struct ProcessState {
  int64_t utime = 0;
  std::string name, host, state;
  int32_t pid = 0, restarts = 0;
  int64_t handled = 0, rejected = 0, dropped = 0;
  double cpu_percent = 0.0, rss_mb = 0.0;
};
/// foxglove.Log: "NAME@HOST (pid P): OLD -> NEW"; crashed is an ERROR, restarting a WARNING.
nlohmann::json processLog(const ProcessState& status, const std::string& previous_state);
/// polarslam.ProcessStatus.
nlohmann::json processStatus(const ProcessState& status);

/// A goal a client published as JSON: {"x", "y"[, "theta"]}, or the position of a Foxglove-style
/// {"pose": {"position": …}}, {"position": …} or {"point": …} (theta NaN unless given). Returns an
/// error string (empty = ok); coordinates must be finite.
std::string goalFromJson(const nlohmann::json& payload, Vec2& position, double& theta);

}  // namespace polarslam::foxglove
