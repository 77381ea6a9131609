#include "io/text_fields.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

namespace polarslam {
namespace {

bool isDigit(char c) { return c >= '0' && c <= '9'; }

/// [sign] digits [. digits] → µs, exactly; nullopt for anything else (e.g. an exponent).
std::optional<int64_t> parsePlainDecimalSeconds(std::string_view s) {
  bool negative = false;
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) {
    negative = s[0] == '-';
    s.remove_prefix(1);
  }
  const size_t dot = s.find('.');
  const std::string_view whole = s.substr(0, dot);
  const std::string_view fraction = dot == std::string_view::npos ? std::string_view{} : s.substr(dot + 1);
  if (whole.empty() && fraction.empty()) return std::nullopt;
  if (whole.size() > 12) return std::nullopt;  // beyond ~31 000 years: not a timestamp
  int64_t seconds = 0;
  for (char c : whole) {
    if (!isDigit(c)) return std::nullopt;
    seconds = seconds * 10 + (c - '0');
  }
  int64_t micros = 0;
  bool round_up = false;
  for (size_t i = 0; i < fraction.size(); ++i) {
    const char c = fraction[i];
    if (!isDigit(c)) return std::nullopt;
    if (i < 6) micros = micros * 10 + (c - '0');
    if (i == 6) round_up = c >= '5';
  }
  for (size_t i = fraction.size(); i < 6; ++i) micros *= 10;
  const int64_t magnitude = seconds * 1000000 + micros + (round_up ? 1 : 0);
  return negative ? -magnitude : magnitude;
}

}  // namespace

TextFormatError::TextFormatError(const std::string& file, int line, const std::string& message)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + message), file_(file), line_(line) {}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

std::optional<double> parseFiniteDouble(std::string_view field) {
  if (!field.empty() && field[0] == '+') field.remove_prefix(1);
  if (field.empty() || field[0] == '+') return std::nullopt;
  double value = 0.0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (ec != std::errc{} || end != field.data() + field.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<int64_t> parseSecondsAsUtime(std::string_view field) {
  if (auto exact = parsePlainDecimalSeconds(field)) return exact;
  const std::optional<double> seconds = parseFiniteDouble(field);
  if (!seconds || std::abs(*seconds) > 1e12) return std::nullopt;
  return static_cast<int64_t>(std::llround(*seconds * 1e6));
}

std::string formatUtimeAsSeconds(int64_t utime) {
  // Magnitude in unsigned arithmetic so that INT64_MIN does not overflow.
  const bool negative = utime < 0;
  const uint64_t magnitude = negative ? 0 - static_cast<uint64_t>(utime) : static_cast<uint64_t>(utime);
  // Zero padding built by append, not insert: GCC 12 -O3 reports a false -Wrestrict on insert.
  const std::string fraction = std::to_string(magnitude % 1000000);
  std::string text = negative ? "-" : "";
  text += std::to_string(magnitude / 1000000);
  text += '.';
  text.append(6 - fraction.size(), '0');
  text += fraction;
  return text;
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw std::runtime_error("cannot read '" + path + "'");
  return content.str();
}

void rejectBinaryContent(std::string_view text, const std::string& name) {
  for (size_t i = 0; i < text.size(); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if ((byte >= 0x20 && byte != 0x7f) || byte == '\t' || byte == '\r' || byte == '\n') continue;
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(i), '\n'));
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", byte);
    throw TextFormatError(name, line, std::string("binary content (byte ") + hex + "), not a text file");
  }
}

}  // namespace polarslam
