#include "common/progress.hpp"

#include <algorithm>
#include <unistd.h>

#include <cstdio>

namespace polarslam {

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)), start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

namespace {
// A bar redrawn with '\r' is noise in a log file or a pipe: only a terminal gets one.
bool stderrIsATerminal() {
  static const bool terminal = isatty(STDERR_FILENO) == 1;
  return terminal;
}
}  // namespace

void ProgressBar::update(double fraction) {
  if (!stderrIsATerminal()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1) || now - last_draw_ < std::chrono::milliseconds(200)) return;
  last_draw_ = now;
  shown_ = true;
  fraction = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%  %.0fs", label_.c_str(), filled,
               "##############################", kWidth - filled, "", static_cast<int>(fraction * 100), elapsed);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (finished_) return;
  finished_ = true;
  if (shown_) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "\r%s [##############################] 100%%  %.1fs\n", label_.c_str(), elapsed);
  }
}

}  // namespace polarslam
