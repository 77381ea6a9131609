#pragma once
// Helpers for the line-oriented text formats polarslam reads (TUM trajectories, Kümmerle
// relations): whitespace splitting, strict number parsing, exact decimal seconds ↔ µs, and
// "file:line: message" errors.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace polarslam {

/// A malformed line in a text file; what() reads "path:line: message".
class TextFormatError : public std::runtime_error {
 public:
  TextFormatError(const std::string& file, int line, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

/// Splits at spaces and tabs; empty fields are dropped.
std::vector<std::string_view> splitFields(std::string_view line);

/// The whole field as a finite double (an optional leading '+' is accepted), else nullopt.
std::optional<double> parseFiniteDouble(std::string_view field);

/// Seconds written in decimal ("1134864645.90321", "-0.5", "1.2e3") to µs, rounded half away
/// from zero. Plain decimals are converted digit by digit, so no precision is lost to doubles.
std::optional<int64_t> parseSecondsAsUtime(std::string_view field);

/// µs as decimal seconds with exactly six fraction digits ("-1.500000").
std::string formatUtimeAsSeconds(int64_t utime);

/// Reads a whole file; throws std::runtime_error naming it when it cannot be read.
std::string readTextFile(const std::string& path);

/// Calls `on_line(line_number, line)` for every line that is neither blank nor a '#' comment.
/// Throws TextFormatError first if the text holds binary content anywhere.
template <typename OnLine>
void forEachDataLine(std::string_view text, const std::string& name, OnLine&& on_line);

/// Throws TextFormatError, naming the line of the first control byte other than tab, carriage
/// return and newline (NUL, escape...): such text is a binary file, not a damaged text file.
void rejectBinaryContent(std::string_view text, const std::string& name);

template <typename OnLine>
void forEachDataLine(std::string_view text, const std::string& name, OnLine&& on_line) {
  rejectBinaryContent(text, name);
  int line_number = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || line[first] == '#') continue;
    on_line(line_number, line);
  }
}

}  // namespace polarslam
