#include "io/safe_path.hpp"

namespace polarslam {

std::filesystem::path pathBelow(const std::filesystem::path& root, const std::string& relative, std::string& why) {
  namespace fs = std::filesystem;
  const fs::path requested(relative);
  if (relative.empty() || requested.is_absolute() || requested.has_root_name()) {
    why = "'" + relative + "' is not a relative path";
    return {};
  }
  for (const fs::path& part : requested) {
    if (part == ".." || part == ".") {
      why = "'" + relative + "' contains '" + part.string() + "'";
      return {};
    }
  }
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(root, ec);
  const fs::path target = fs::weakly_canonical(root / requested, ec);
  if (ec) {
    why = "'" + relative + "': " + ec.message();
    return {};
  }
  const auto [base_end, target_it] = std::mismatch(base.begin(), base.end(), target.begin(), target.end());
  if (base_end != base.end()) {
    why = "'" + relative + "' leads out of " + base.string();
    return {};
  }
  return root / requested;
}

}  // namespace polarslam
