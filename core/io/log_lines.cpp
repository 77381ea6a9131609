#include "io/log_lines.hpp"

#include <zlib.h>

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "io/text_fields.hpp"

namespace polarslam {
namespace {

std::streamoff streamSize(std::istream& in) {
  const auto start = in.tellg();
  if (start < 0) return -1;
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(start);
  return end < 0 ? -1 : static_cast<std::streamoff>(end - start);
}

}  // namespace

std::string quotedField(std::string_view field) {
  constexpr size_t kMaxShown = 24;
  std::string s(field.substr(0, kMaxShown));
  if (field.size() > kMaxShown) s += "...";
  return "'" + s + "'";
}

bool parseLogDouble(std::string_view text, double& value) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

bool parseLogInteger(std::string_view text, int64_t& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

namespace {
// Why a field that parseLogDouble refused is not a usable double: "1e309" is a number, too big.
std::string numberProblem(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double ignored = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), ignored);
  const bool whole = end == text.data() + text.size();
  return ec == std::errc::result_out_of_range && whole ? " is out of range of a double" : " is not a number";
}
}  // namespace

double FieldCursor::number(const char* what) {
  const std::string_view f = take(what);
  double v = 0.0;
  if (!parseLogDouble(f, v)) fail(std::string(what) + " " + quotedField(f) + numberProblem(f));
  return v;
}

double FieldCursor::finite(const char* what) {
  const double v = number(what);
  if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
  return v;
}

float FieldCursor::range(size_t index) {
  const std::string_view f = take("range");
  double v = 0.0;
  if (!parseLogDouble(f, v)) fail("range " + std::to_string(index) + " " + quotedField(f) + numberProblem(f));
  return static_cast<float>(v);
}

std::vector<float> FieldCursor::ranges(size_t n) {
  std::vector<float> values(n);
  for (size_t i = 0; i < n; ++i) values[i] = range(i);
  return values;
}

int64_t FieldCursor::integer(const char* what, int64_t min, int64_t max) {
  const std::string_view f = take(what);
  int64_t n = 0;
  if (!parseLogInteger(f, n)) fail(std::string(what) + " " + quotedField(f) + " is not an integer");
  if (n < min || n > max)
    fail(std::string(what) + " " + std::to_string(n) + " out of range [" + std::to_string(min) + ", " +
         std::to_string(max) + "]");
  return n;
}

int64_t FieldCursor::timestamp(const char* what) {
  const std::string_view f = take(what);
  int64_t utime = 0;
  if (!parseSecondsToUtime(f, utime)) fail(std::string(what) + " " + quotedField(f) + " is not a time in seconds");
  return utime;
}

void FieldCursor::skip(size_t n) {
  if (next_ + n > fields_.size()) fail("line ends early");
  next_ += n;
}

void FieldCursor::expectTotal(size_t total, const char* formula) const {
  if (fields_.size() != total)
    fail("expected " + std::string(formula) + " = " + std::to_string(total) + " fields, got " +
         std::to_string(fields_.size()));
}

void FieldCursor::fail(const std::string& why) const { throw MalformedLine{std::string(kind_) + ": " + why}; }

std::string_view FieldCursor::take(const char* what) {
  if (next_ >= fields_.size()) fail(std::string("line ends before ") + what);
  return fields_[next_++];
}

void checkScan(const LaserScan& scan, const FieldCursor& cursor) {
  const std::string why = validateScan(scan);
  if (!why.empty()) cursor.fail(why);
}

void recordMalformed(CarmenLog& log, int64_t line, std::string reason) {
  ++log.malformed_count;
  if (log.malformed.size() < CarmenLog::kMaxReportedIssues) log.malformed.push_back({line, std::move(reason)});
}

void numberSequences(CarmenLog& log) {
  int64_t laser_seq = 0, odometry_seq = 0;
  for (CarmenEvent& e : log.events) {
    if (auto* scan = std::get_if<LaserScan>(&e.data)) scan->seq = laser_seq++;
    else std::get<OdometryReading>(e.data).seq = odometry_seq++;
  }
}

void forEachLogLine(std::istream& in, CarmenLog& log, const std::function<void(double)>& progress,
                    const std::function<void(const std::vector<std::string_view>&)>& on_line) {
  const std::streamoff total = progress ? streamSize(in) : -1;
  std::streamoff consumed = 0;
  std::string line;
  while (std::getline(in, line)) {
    ++log.lines;
    consumed += static_cast<std::streamoff>(line.size() + 1);
    if (total > 0 && log.lines % 256 == 0) progress(static_cast<double>(consumed) / static_cast<double>(total));
    const std::vector<std::string_view> fields = splitFields(line);
    if (fields.empty() || fields.front().front() == '#') {
      ++log.comment_lines;
      continue;
    }
    try {
      on_line(fields);
    } catch (const MalformedLine& m) {
      recordMalformed(log, log.lines, m.reason);
    }
  }
  if (progress) progress(1.0);
}

std::string readMaybeGzipFile(const std::string& path, const std::string& what) {
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) throw std::runtime_error("cannot open " + what + " '" + path + "'");
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const int n = gzread(file, buffer, sizeof buffer);
    if (n < 0) {
      int code = 0;
      const std::string message = gzerror(file, &code);
      gzclose(file);
      throw std::runtime_error("cannot read " + what + " '" + path + "': " + message);
    }
    if (n == 0) break;
    text.append(buffer, static_cast<size_t>(n));
  }
  // A gzip file cut short reads as a clean end of file; gzclose reports it as Z_BUF_ERROR.
  if (gzclose(file) == Z_BUF_ERROR) throw std::runtime_error("cannot read " + what + " '" + path + "': truncated gzip data");
  return text;
}

}  // namespace polarslam
