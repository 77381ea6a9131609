#include "io/tum.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "io/atomic_file.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {

constexpr size_t kTumFields = 8;

PoseStamped parseTumLine(std::string_view line, const std::string& name, int line_number) {
  const std::vector<std::string_view> fields = splitFields(line);
  if (fields.size() != kTumFields)
    throw TextFormatError(name, line_number, "expected 8 fields 't x y z qx qy qz qw', found " +
                                                 std::to_string(fields.size()));
  PoseStamped pose;
  const std::optional<int64_t> utime = parseSecondsAsUtime(fields[0]);
  if (!utime) throw TextFormatError(name, line_number, "bad timestamp '" + std::string(fields[0]) + "'");
  pose.utime = *utime;
  double values[kTumFields - 1];
  static const char* const kNames[] = {"x", "y", "z", "qx", "qy", "qz", "qw"};
  for (size_t i = 1; i < kTumFields; ++i) {
    const std::optional<double> v = parseFiniteDouble(fields[i]);
    if (!v)
      throw TextFormatError(name, line_number,
                            std::string("bad ") + kNames[i - 1] + " '" + std::string(fields[i]) + "'");
    values[i - 1] = *v;
  }
  const double norm = std::sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                                values[6] * values[6]);
  if (norm < 1e-6) throw TextFormatError(name, line_number, "quaternion has zero length");
  pose.pose = Pose2(values[0], values[1], yawFromQuaternion(values[3], values[4], values[5], values[6]));
  return pose;
}

std::string formatTumLine(const PoseStamped& p) {
  const YawQuaternion q = quaternionFromYaw(p.pose.theta);
  char numbers[160];
  std::snprintf(numbers, sizeof numbers, " %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p.pose.x, p.pose.y, 0.0,
                q.qx, q.qy, q.qz, q.qw);
  return formatUtimeAsSeconds(p.utime) + numbers;
}

}  // namespace

YawQuaternion quaternionFromYaw(double yaw) {
  YawQuaternion q;
  q.qz = std::sin(0.5 * yaw);
  q.qw = std::cos(0.5 * yaw);
  if (q.qw < 0.0) {  // one canonical sign, so equal yaws give equal text
    q.qz = -q.qz;
    q.qw = -q.qw;
  }
  return q;
}

double yawFromQuaternion(double qx, double qy, double qz, double qw) {
  return std::atan2(2.0 * (qw * qz + qx * qy), qw * qw + qx * qx - qy * qy - qz * qz);
}

std::vector<PoseStamped> parseTumTrajectory(std::string_view text, const std::string& name) {
  std::vector<PoseStamped> poses;
  forEachDataLine(text, name, [&](int line_number, std::string_view line) {
    poses.push_back(parseTumLine(line, name, line_number));
  });
  return poses;
}

std::vector<PoseStamped> readTumTrajectory(const std::string& path) {
  return parseTumTrajectory(readTextFile(path), path);
}

std::string formatTumTrajectory(const std::vector<PoseStamped>& poses) {
  std::string text = "# t x y z qx qy qz qw\n";
  text.reserve(poses.size() * 100 + text.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const Pose2& p = poses[i].pose;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.theta))
      throw std::invalid_argument("TUM trajectory: pose " + std::to_string(i) + " at t = " +
                                  formatUtimeAsSeconds(poses[i].utime) + " s is not finite");
    text += formatTumLine(poses[i]);
  }
  return text;
}

void writeTumTrajectory(const std::string& path, const std::vector<PoseStamped>& poses) {
  writeFileAtomically(path, formatTumTrajectory(poses));
}

}  // namespace polarslam
