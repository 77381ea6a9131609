#include "common/path_messages.hpp"

#include <cmath>

namespace polarslam {
namespace {

void append(polarslam::path_t& msg, int64_t pose_utime, const Pose2& pose, int8_t source) {
  msg.pose_utime.push_back(pose_utime);
  msg.x.push_back(pose.x);
  msg.y.push_back(pose.y);
  msg.theta.push_back(pose.theta);
  msg.source.push_back(source);
}

polarslam::path_t emptyPath(int64_t utime, int64_t seq) {
  polarslam::path_t msg;
  msg.utime = utime;
  msg.seq = seq;
  msg.frame = "map";
  msg.goal_utime = 0;
  msg.goal_exact = 0;
  msg.num_poses = 0;
  return msg;
}

}  // namespace

polarslam::path_t toLcmPath(const std::vector<int64_t>& scan_utimes, const std::vector<RegeneratedPose>& poses,
                            int64_t utime, int64_t seq) {
  polarslam::path_t msg = emptyPath(utime, seq);
  for (size_t i = 0; i < poses.size() && i < scan_utimes.size(); ++i)
    append(msg, scan_utimes[i], poses[i].pose, static_cast<int8_t>(poses[i].source));
  msg.num_poses = static_cast<int32_t>(msg.x.size());
  return msg;
}

polarslam::path_t toLcmPath(const std::vector<Vec2>& waypoints, int64_t goal_utime, bool goal_exact, int64_t utime,
                            int64_t seq) {
  polarslam::path_t msg = emptyPath(utime, seq);
  msg.goal_utime = goal_utime;
  msg.goal_exact = goal_exact ? 1 : 0;
  for (size_t i = 0; i < waypoints.size(); ++i) {
    const Vec2 d = i + 1 < waypoints.size() ? Vec2(waypoints[i + 1] - waypoints[i])
                                            : (i > 0 ? Vec2(waypoints[i] - waypoints[i - 1]) : Vec2(1.0, 0.0));
    append(msg, 0, Pose2(waypoints[i].x(), waypoints[i].y(), std::atan2(d.y(), d.x())), polarslam::path_t::PLANNED);
  }
  msg.num_poses = static_cast<int32_t>(msg.x.size());
  return msg;
}

polarslam::path_t toLcmPath(const std::vector<PoseStamped>& trajectory, int64_t utime, int64_t seq) {
  polarslam::path_t msg = emptyPath(utime, seq);
  for (const PoseStamped& p : trajectory) append(msg, p.utime, p.pose, polarslam::path_t::FINAL);
  msg.num_poses = static_cast<int32_t>(msg.x.size());
  return msg;
}

std::string fromLcm(const polarslam::path_t& msg, std::vector<PoseStamped>& poses) {
  std::vector<Vec2> positions;
  if (std::string why = fromLcm(msg, positions); !why.empty()) return why;
  std::vector<PoseStamped> out(positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!std::isfinite(msg.theta[i])) return "path: non-finite heading";
    out[i].utime = msg.pose_utime[i];
    out[i].pose = Pose2(positions[i].x(), positions[i].y(), msg.theta[i]);
  }
  poses = std::move(out);
  return {};
}

std::string fromLcm(const polarslam::path_t& msg, std::vector<Vec2>& positions) {
  if (msg.num_poses < 0 || msg.num_poses > 1000000) return "path: bad num_poses";
  const auto n = static_cast<size_t>(msg.num_poses);
  if (msg.x.size() != n || msg.y.size() != n || msg.theta.size() != n || msg.source.size() != n ||
      msg.pose_utime.size() != n)
    return "path: array lengths disagree with num_poses";
  std::vector<Vec2> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(msg.x[i]) || !std::isfinite(msg.y[i]) || std::abs(msg.x[i]) > 1e6 || std::abs(msg.y[i]) > 1e6)
      return "path: non-finite or absurd position";
    out.emplace_back(msg.x[i], msg.y[i]);
  }
  positions = std::move(out);
  return {};
}

}  // namespace polarslam
