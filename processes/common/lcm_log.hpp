#pragma once
// Reading and writing LCM log files through LCM's own LogFile, keeping original timestamps.
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
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

class LcmLogReader {
 public:
  explicit LcmLogReader(const std::string& path);
  /// Next event, or false at the end of the log (a truncated last event also ends it).
  bool next(LogEvent& event);
  /// Fraction of the file read so far, for progress bars.
  double progress() const;

 private:
  std::unique_ptr<lcm::LogFile> log_;
  long size_ = 0;
};

class LcmLogWriter {
 public:
  /// Writes to path + ".tmp" and renames on close(), so a crash never leaves a half log in place.
  explicit LcmLogWriter(const std::string& path);
  ~LcmLogWriter();
  void writeRaw(const std::string& channel, int64_t utime, const void* data, size_t size);
  template <typename MsgT>
  void write(const std::string& channel, int64_t utime, const MsgT& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    writeRaw(channel, utime, buf.data(), buf.size());
  }
  void close();
  int64_t events() const { return events_; }

 private:
  std::string path_, tmp_path_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t events_ = 0;
};

}  // namespace polarslam
