#pragma once
// TUM RGB-D trajectory files, as `evo` reads them: one pose per line, `t x y z qx qy qz qw`,
// t in seconds. polarslam is 2D: z = 0 and the quaternion is a pure yaw rotation on write; on
// read, z and any roll/pitch are ignored and the yaw is extracted.
#include <string>
#include <string_view>
#include <vector>

#include "geometry/features.hpp"

namespace polarslam {

struct YawQuaternion { double qx = 0.0, qy = 0.0, qz = 0.0, qw = 1.0; };

YawQuaternion quaternionFromYaw(double yaw);
/// Yaw (rotation about z, ZYX convention) of a unit or non-unit quaternion.
double yawFromQuaternion(double qx, double qy, double qz, double qw);

/// Parses TUM text; blank lines and '#' comments are skipped. Covariances are left zero.
/// Throws TextFormatError ("name:line: ...") for a malformed line.
std::vector<PoseStamped> parseTumTrajectory(std::string_view text, const std::string& name);
std::vector<PoseStamped> readTumTrajectory(const std::string& path);

/// Formats poses as TUM text: a '#' header, then t with µs precision (6 decimals), x y z in m
/// (9 decimals), the quaternion (9 decimals). Throws std::invalid_argument for a non-finite pose.
std::string formatTumTrajectory(const std::vector<PoseStamped>& poses);
/// Writes atomically (temporary file + rename).
void writeTumTrajectory(const std::string& path, const std::vector<PoseStamped>& poses);

}  // namespace polarslam
