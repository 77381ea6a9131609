#pragma once
// Reading and writing LCM log files through LCM's own LogFile, keeping original timestamps.
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/lcm_decode.hpp"

namespace polarslam {

struct LogEvent {
  int64_t utime = 0;  ///< the log's event timestamp (µs)
  std::string channel;
  std::vector<uint8_t> data;

  /// Decodes the payload as MsgT; false when it is not one (wrong type or truncated).
  template <typename MsgT>
  bool decode(MsgT& msg) const {
    return decodeLcm(msg, data.data(), data.size());
  }
};

/// Reads LCM's log format (lcm-logger's files) itself, so that it can say where a log is broken:
/// each event is a 28-byte big-endian header (sync word 0xEDA1DA01, event number, timestamp,
/// channel length, data length), the channel, then the data.
class LcmLogReader {
 public:
  /// Throws when the file cannot be read, is empty, or does not start as an LCM log.
  explicit LcmLogReader(const std::string& path);
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;
  ~LcmLogReader();

  /// Next event, or false at the end of the log. A corrupt event in the middle is skipped up to
  /// the next sync word, a torn last event ends the log; both leave a warning.
  bool next(LogEvent& event);
  /// Fraction of the file read so far, for progress bars.
  double progress() const;
  int64_t events() const { return events_; }
  /// What was wrong with the file, each with its byte offset (empty for an intact log).
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The warnings as "warning: ..." lines on stderr.
  void printWarnings() const;

 private:
  bool readHeaderAt(int64_t offset, int64_t& timestamp, uint32_t& channel_length, uint32_t& data_length);
  bool resyncAfter(int64_t offset);
  void warn(const std::string& what);

  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t size_ = 0, offset_ = 0, events_ = 0;
  std::vector<std::string> warnings_;
};

class LcmLogWriter {
 public:
  /// Writes to path + ".tmp" and renames on close(), so a crash never leaves a half log in place.
  explicit LcmLogWriter(const std::string& path);
  /// Without a successful close() (an exception, a failed write) the temporary file is removed:
  /// nothing appears under the final name unless it is complete.
  ~LcmLogWriter();
  void writeRaw(const std::string& channel, int64_t utime, const void* data, size_t size);
  template <typename MsgT>
  void write(const std::string& channel, int64_t utime, const MsgT& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    writeRaw(channel, utime, buf.data(), buf.size());
  }
  /// Flushes, checks that every byte reached the file (a full disk shows here) and renames the
  /// log to its final name; throws, and leaves no file, when anything failed.
  void close();
  int64_t events() const { return events_; }

 private:
  std::string path_, tmp_path_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t events_ = 0;
};

}  // namespace polarslam
