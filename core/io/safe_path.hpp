#pragma once
// Paths that come from the network (GRID_REQUEST.out_dir) must stay below a folder the operator
// chose: a relative path of plain names, no "..", no absolute path, no symbolic link on the way
// that leads out.
#include <filesystem>
#include <string>

namespace polarslam {

/// `root / relative` when `relative` is a relative path of plain names that stays below `root`
/// (symbolic links that exist are followed for the check); otherwise an empty path and `why`.
std::filesystem::path pathBelow(const std::filesystem::path& root, const std::string& relative, std::string& why);

}  // namespace polarslam
