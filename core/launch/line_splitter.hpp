#pragma once
// Cuts a child's output stream into lines for prefixing and logging.
#include <cstddef>
#include <string>
#include <vector>

namespace polarslam {

class LineSplitter {
 public:
  /// Lines longer than `max_line` bytes are cut, so a process that never prints '\n' still shows.
  explicit LineSplitter(size_t max_line = 4096) : max_line_(max_line) {}

  /// Appends bytes; returns the lines completed by them, without '\n' (and without a '\r' before it).
  std::vector<std::string> feed(const char* data, size_t size);
  /// The unfinished last line, if any (at end of stream).
  std::vector<std::string> finish();

 private:
  size_t max_line_;
  std::string pending_;
};

}  // namespace polarslam
