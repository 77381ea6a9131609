#include "console.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <iostream>

#include "launch/status_view.hpp"

namespace polarslam {
namespace {

constexpr size_t kRecentLines = 500;
constexpr auto kLiveRedraw = std::chrono::milliseconds(500);

struct TerminalSize {
  size_t rows = 24, cols = 80;
};

TerminalSize terminalSize() {
  winsize ws{};
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_row > 0 && ws.ws_col > 0) return {ws.ws_row, ws.ws_col};
  return {};
}

std::string fitted(const std::string& s, size_t width) { return s.size() > width ? s.substr(0, width) : s; }

}  // namespace

Console::Console(bool live_table, std::string title, double status_period_s)
    : live_(live_table),
      title_(std::move(title)),
      period_(live_table ? std::chrono::duration_cast<LaunchClock::duration>(kLiveRedraw)
                         : std::chrono::duration_cast<LaunchClock::duration>(std::chrono::duration<double>(status_period_s))),
      next_refresh_(LaunchClock::now() + period_) {
  if (live_) std::cout << "\x1b[?1049h\x1b[?25l" << std::flush;  // alternate screen, hidden cursor
}

Console::~Console() {
  if (live_ && !finished_) std::cout << "\x1b[?25h\x1b[?1049l" << std::flush;
}

void Console::line(const std::string& name, const std::string& text) {
  std::string prefixed = "[" + name + "] " + text;
  if (!live_) {
    std::cout << prefixed << '\n';
    return;
  }
  recent_.push_back(printable(prefixed));
  if (recent_.size() > kRecentLines) recent_.pop_front();
}

void Console::refresh(const ProcessTable& table, LaunchClock::time_point now, bool force) {
  if (now < next_refresh_ && !(force && live_)) {
    if (!live_) std::cout << std::flush;
    return;
  }
  next_refresh_ = now + period_;
  if (live_) {
    redraw(table, now);
    return;
  }
  for (const auto& row : formatStatusTable(table, now)) std::cout << "[status] " << row << '\n';
  std::cout << std::flush;
}

void Console::redraw(const ProcessTable& table, LaunchClock::time_point now) {
  const TerminalSize size = terminalSize();
  std::vector<std::string> screen{title_, ""};
  for (auto& row : formatStatusTable(table, now)) screen.push_back(std::move(row));
  screen.push_back("");
  screen.push_back("-- latest output (Ctrl-C stops everything) --");
  const size_t room = size.rows > screen.size() + 1 ? size.rows - screen.size() - 1 : 0;
  const size_t first = recent_.size() > room ? recent_.size() - room : 0;
  for (size_t i = first; i < recent_.size(); ++i) screen.push_back(recent_[i]);
  if (screen.size() >= size.rows) screen.resize(size.rows - 1);  // a last '\n' on the bottom row would scroll
  std::string out = "\x1b[H";
  for (const auto& row : screen) out += fitted(row, size.cols) + "\x1b[K\n";
  out += "\x1b[J";
  std::cout << out << std::flush;
}

void Console::finish(const ProcessTable& table, LaunchClock::time_point now) {
  if (live_) std::cout << "\x1b[?25h\x1b[?1049l";
  finished_ = true;
  std::cout << title_ << '\n';
  for (const auto& row : formatStatusTable(table, now)) std::cout << (live_ ? "" : "[status] ") << row << '\n';
  std::cout << std::flush;
}

}  // namespace polarslam
