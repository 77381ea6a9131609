#pragma once
// Files a test writes for a reader to open: under gtest's temp dir, named for this process (ctest
// runs the tests of one file in parallel), and removed when the object goes.
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace polarslam {

class ScratchFiles {
 public:
  ScratchFiles() = default;
  ScratchFiles(const ScratchFiles&) = delete;
  ScratchFiles& operator=(const ScratchFiles&) = delete;
  ~ScratchFiles() {
    std::error_code ignored;
    for (const std::string& path : written_) std::filesystem::remove(path, ignored);
  }

  /// Where `name` is written (whether or not it has been yet).
  std::string path(const std::string& name) const {
    return ::testing::TempDir() + "/" + std::to_string(::getpid()) + "-" + name;
  }
  /// Writes `text` as `name`; its path.
  std::string write(const std::string& name, const std::string& text) {
    const std::string where = path(name);
    std::ofstream(where) << text;
    written_.insert(where);
    return where;
  }

 private:
  std::set<std::string> written_;
};

}  // namespace polarslam
