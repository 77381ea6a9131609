#pragma once
// Relations files of Kümmerle et al. 2009 (docs/algorithms.md §20.1): one relation per line,
// `t1 t2 x y z roll pitch yaw`, the rigid motion from the pose at t1 to the pose at t2 in the
// frame of the pose at t1. Timestamps are the log's ipc_timestamp in seconds.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "geometry/pose2.hpp"

namespace polarslam {

struct Relation {
  int64_t t1 = 0, t2 = 0;  ///< µs
  double x = 0.0, y = 0.0, z = 0.0;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;
  int line = 0;            ///< line in the file it came from (0 = not from a file)

  Pose2 motion() const { return {x, y, wrapAngle(yaw)}; }
};

/// Parses relations text. Blank lines and '#' comments are skipped. Malformed, truncated or
/// binary content throws TextFormatError ("name:line: ..."); text without any relation throws
/// too, since it is surely not a relations file.
std::vector<Relation> parseRelations(std::string_view text, const std::string& name);
std::vector<Relation> readRelations(const std::string& path);

}  // namespace polarslam
