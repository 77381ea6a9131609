#pragma once
// One entry point for the 2D range logs polarslam imports: CARMEN (.clf), CMU Wean Hall, Duke
// DP-SLAM and Mines ParisTech (data README). Every reader gives the same in-memory log (RangeLog,
// which is CarmenLog) in SI units: metres, radians, µs. Files may be gzip-compressed.
#include <optional>
#include <string>
#include <string_view>

#include "io/carmen.hpp"
#include "io/cmu_log.hpp"
#include "io/duke_log.hpp"
#include "io/mines_log.hpp"

namespace polarslam {

using RangeLog = CarmenLog;
using RangeLogEvent = CarmenEvent;

enum class RangeLogFormat { Auto, Carmen, Cmu, Duke, Mines };

/// "auto", "carmen", "cmu", "duke", "mines".
std::string rangeLogFormatName(RangeLogFormat format);
std::optional<RangeLogFormat> parseRangeLogFormat(std::string_view name);

struct RangeLogOptions {
  CarmenOptions carmen;
  CmuOptions cmu;
  DukeOptions duke;
  MinesOptions mines;
};

/// The format of a log's text, from its first recognisable data line: CARMEN message names
/// (FLASER, ROBOTLASER1, ODOM, PARAM...), CMU "O"/"L", Duke "Odometry"/"Laser", or a Mines line
/// of 706/707 numeric columns (integer timestamp and wheel counts). A text without data lines falls back on the extension of `name`
/// (.clf = CARMEN, .dat = Mines). Throws TextFormatError naming the file and line otherwise
/// (binary content, or a first data line of no known format).
RangeLogFormat detectRangeLogFormat(std::string_view text, const std::string& name);

/// Reads a range log file (plain or gzip) in the given format, detecting it for Auto. Throws
/// std::runtime_error naming the file when it cannot be read or is not a range log.
RangeLog readRangeLogFile(const std::string& path, RangeLogFormat format = RangeLogFormat::Auto,
                          const RangeLogOptions& options = {});
/// The same on text already in memory; `name` names it in errors.
RangeLog readRangeLogText(const std::string& text, const std::string& name, RangeLogFormat format,
                          const RangeLogOptions& options = {});

}  // namespace polarslam
