#pragma once
// Shared machinery of the line-oriented range log readers (CARMEN, CMU, Duke, Mines): a field
// cursor that names the line kind and field in every complaint, the per-line loop that counts
// comments and malformed lines (never fatal), sequence numbering, and reading plain or gzip text.
#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "io/carmen.hpp"

namespace polarslam {

/// Why a line is malformed; thrown inside a line parser and caught per line by forEachLogLine.
struct MalformedLine {
  std::string reason;
};

/// A field shown in a complaint, cut to a readable length and quoted.
std::string quotedField(std::string_view field);

/// The whole text as a double (an optional leading '+' is accepted; inf and nan are accepted).
bool parseLogDouble(std::string_view text, double& value);
/// The whole text as a decimal integer.
bool parseLogInteger(std::string_view text, int64_t& value);

/// Reads the fields of one line in order, naming the line kind and field in every complaint.
class FieldCursor {
 public:
  /// `first` is the index of the first data field (1 when field 0 names the message).
  FieldCursor(std::string_view kind, const std::vector<std::string_view>& fields, size_t first = 1)
      : kind_(kind), fields_(fields), next_(first) {}

  double number(const char* what);
  double finite(const char* what);
  /// A range reading: any number (NaN/inf become "no return" downstream).
  float range(size_t index);
  /// The next n range readings.
  std::vector<float> ranges(size_t n);
  /// An integer in [min, max].
  int64_t integer(const char* what, int64_t min, int64_t max);
  int64_t count(const char* what, int64_t max) { return integer(what, 0, max); }
  /// Decimal seconds to µs, exactly.
  int64_t timestamp(const char* what);
  void skip(size_t n = 1);
  /// Checks the total field count once the variable-length parts are known.
  void expectTotal(size_t total, const char* formula) const;
  [[noreturn]] void fail(const std::string& why) const;

 private:
  std::string_view take(const char* what);
  std::string_view kind_;
  const std::vector<std::string_view>& fields_;
  size_t next_;
};

/// Fails the line (through the cursor) when validateScan rejects the scan.
void checkScan(const LaserScan& scan, const FieldCursor& cursor);

/// Counts a malformed line; the first CarmenLog::kMaxReportedIssues are kept with their reason.
void recordMalformed(CarmenLog& log, int64_t line, std::string reason);

/// Numbers laser scans and odometry readings in file order, each kind from 0.
void numberSequences(CarmenLog& log);

/// Calls `on_line(fields)` for every line that is neither blank nor a '#' comment, with log.lines
/// holding its 1-based number; counts comments, reports progress and records a MalformedLine
/// thrown by `on_line` against the line instead of stopping.
void forEachLogLine(std::istream& in, CarmenLog& log, const std::function<void(double)>& progress,
                    const std::function<void(const std::vector<std::string_view>&)>& on_line);

/// Reads a whole file, decompressing it when it is gzip (zlib reads plain files unchanged).
/// Throws std::runtime_error naming the file (and `what` it should be) when it cannot be read.
std::string readMaybeGzipFile(const std::string& path, const std::string& what);

}  // namespace polarslam
