#pragma once
// A progress bar on stderr for offline commands; it appears only once a run has lasted a second.
#include <chrono>
#include <string>

namespace polarslam {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  void update(double fraction);
  void finish();

 private:
  std::string label_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool shown_ = false, finished_ = false;
};

}  // namespace polarslam
