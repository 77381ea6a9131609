#include "io/range_log.hpp"

#include <algorithm>
#include <cctype>
#include <sstream>

#include "io/log_lines.hpp"
#include "io/text_fields.hpp"

namespace polarslam {
namespace {

bool endsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

bool isCarmenMessageName(std::string_view word) {
  if (word.size() < 3 || word.front() < 'A' || word.front() > 'Z') return false;
  return std::all_of(word.begin(), word.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

bool isInteger(std::string_view word) {
  int64_t v = 0;
  return parseLogInteger(word, v);
}

bool isNumber(std::string_view word) {
  double v = 0.0;
  return parseLogDouble(word, v);
}

std::optional<RangeLogFormat> formatOfLine(const std::vector<std::string_view>& fields, const MinesOptions& mines) {
  const std::string_view first = fields.front();
  if (first == "O" || first == "L") return RangeLogFormat::Cmu;
  if (first == "Odometry" || first == "Laser") return RangeLogFormat::Duke;
  if (isCarmenMessageName(first)) return RangeLogFormat::Carmen;
  const size_t columns = mines.first_range_column + mines.beams;
  // Mines: timestamp and wheel counts are integers; some unused columns hold decimals (167.2).
  if ((fields.size() == columns || fields.size() == columns + 1) && isInteger(fields[0]) && isInteger(fields[2]) &&
      isInteger(fields[3]) && std::all_of(fields.begin(), fields.end(), isNumber))
    return RangeLogFormat::Mines;
  return std::nullopt;
}

}  // namespace

std::string rangeLogFormatName(RangeLogFormat format) {
  switch (format) {
    case RangeLogFormat::Auto: return "auto";
    case RangeLogFormat::Carmen: return "carmen";
    case RangeLogFormat::Cmu: return "cmu";
    case RangeLogFormat::Duke: return "duke";
    case RangeLogFormat::Mines: return "mines";
  }
  return "?";
}

std::optional<RangeLogFormat> parseRangeLogFormat(std::string_view name) {
  for (RangeLogFormat f : {RangeLogFormat::Auto, RangeLogFormat::Carmen, RangeLogFormat::Cmu, RangeLogFormat::Duke,
                           RangeLogFormat::Mines})
    if (name == rangeLogFormatName(f)) return f;
  return std::nullopt;
}

RangeLogFormat detectRangeLogFormat(std::string_view text, const std::string& name) {
  // Binary content (an LCM log given by mistake, say) is reported before any guessing.
  constexpr size_t kLookahead = 1 << 16;
  rejectBinaryContent(text.substr(0, kLookahead), name);
  const MinesOptions mines;
  int line_number = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    const std::vector<std::string_view> fields = splitFields(line);
    if (fields.empty() || fields.front().front() == '#') continue;
    if (const auto format = formatOfLine(fields, mines)) return *format;
    throw TextFormatError(name, line_number,
                          "not a range log: the first data line starts with " + quotedField(fields.front()) + " (" +
                              std::to_string(fields.size()) +
                              " fields); expected CARMEN messages (FLASER, ODOM...), CMU O/L lines, Duke "
                              "Odometry/Laser lines or Mines lines of 707 numeric columns");
  }
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (endsWith(lower, ".gz")) lower.resize(lower.size() - 3);
  if (endsWith(lower, ".clf")) return RangeLogFormat::Carmen;
  if (endsWith(lower, ".dat")) return RangeLogFormat::Mines;
  throw TextFormatError(name, line_number, "not a range log: no data lines, and the name does not tell the format");
}

RangeLog readRangeLogText(const std::string& text, const std::string& name, RangeLogFormat format,
                          const RangeLogOptions& options) {
  if (format == RangeLogFormat::Auto) format = detectRangeLogFormat(text, name);
  std::istringstream in(text);
  switch (format) {
    case RangeLogFormat::Carmen: return readCarmenLog(in, options.carmen);
    case RangeLogFormat::Cmu: return readCmuLog(in, options.cmu);
    case RangeLogFormat::Duke: return readDukeLog(in, options.duke);
    case RangeLogFormat::Mines: return readMinesLog(in, options.mines);
    case RangeLogFormat::Auto: break;
  }
  return {};
}

RangeLog readRangeLogFile(const std::string& path, RangeLogFormat format, const RangeLogOptions& options) {
  return readRangeLogText(readMaybeGzipFile(path, "range log"), path, format, options);
}

}  // namespace polarslam
