#pragma once
// Where the tests find the project's own files (config/, logs/, worlds).
#include <string>

namespace polarslam::testing {

inline std::string sourcePath(const std::string& rel) { return std::string(POLARSLAM_SOURCE_DIR) + "/" + rel; }

}  // namespace polarslam::testing
