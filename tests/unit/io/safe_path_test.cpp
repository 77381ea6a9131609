// pathBelow: a folder named by a network message stays below the operator's folder.
#include <gtest/gtest.h>

#include <filesystem>

#include "io/safe_path.hpp"

namespace polarslam {
namespace {

namespace fs = std::filesystem;

TEST(SafePath, RelativeNamesStayBelowTheRoot) {
  const fs::path root = fs::path(::testing::TempDir()) / "safe-path-root";
  fs::create_directories(root);
  std::string why;
  EXPECT_EQ(pathBelow(root, "maps/today", why), root / "maps/today");
  EXPECT_EQ(pathBelow(root, "new", why), root / "new") << "a folder that does not exist yet is fine";
}

TEST(SafePath, AbsolutePathsDotDotAndLinksOutAreRefused) {
  const fs::path root = fs::path(::testing::TempDir()) / "safe-path-root2";
  fs::remove_all(root);
  fs::create_directories(root);
  fs::create_directory_symlink("/tmp", root / "escape");
  for (const std::string bad : {"/etc", "../outside", "maps/../../outside", "./maps", "", "escape/x"}) {
    std::string why;
    EXPECT_TRUE(pathBelow(root, bad, why).empty()) << "'" << bad << "' accepted";
    EXPECT_FALSE(why.empty()) << bad;
  }
}

}  // namespace
}  // namespace polarslam
