#pragma once
// Finding the program a command runs before forking, so a missing one is reported clearly.
#include <string>

namespace polarslam {

/// The path exec would run for `program`: as given (relative to `working_dir`) when it contains
/// a '/', else the first executable match in the ':'-separated `search_path`. Empty if none.
std::string findExecutable(const std::string& program, const std::string& search_path,
                           const std::string& working_dir);

}  // namespace polarslam
