#include "common/lcm_log.hpp"

#include <cstdio>
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <system_error>

namespace polarslam {

namespace {

constexpr uint32_t kSyncWord = 0xEDA1DA01;
constexpr int kHeaderBytes = 28;
constexpr uint32_t kMaxChannelLength = 1024;
constexpr uint32_t kMaxDataLength = 256u << 20;

uint64_t bigEndian(const uint8_t* bytes, int count) {
  uint64_t value = 0;
  for (int i = 0; i < count; ++i) value = value << 8 | bytes[i];
  return value;
}

}  // namespace

LcmLogReader::LcmLogReader(const std::string& path) : path_(path) {
  std::error_code ec;
  size_ = static_cast<int64_t>(std::filesystem::file_size(path, ec));
  if (ec) throw std::runtime_error("cannot open LCM log '" + path + "': " + ec.message());
  if (size_ == 0) throw std::runtime_error("'" + path + "' is empty, not an LCM log");
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw std::runtime_error("cannot open LCM log '" + path + "'");
  uint8_t sync[4] = {0, 0, 0, 0};
  if (std::fread(sync, 1, 4, file_) != 4 || bigEndian(sync, 4) != kSyncWord) {
    std::fclose(file_);
    file_ = nullptr;
    throw std::runtime_error("'" + path + "' is not an LCM log (it does not start with an LCM event)");
  }
}

LcmLogReader::~LcmLogReader() {
  if (file_) std::fclose(file_);
}

void LcmLogReader::warn(const std::string& what) { warnings_.push_back(path_ + ": " + what); }

bool LcmLogReader::readHeaderAt(int64_t offset, int64_t& timestamp, uint32_t& channel_length, uint32_t& data_length) {
  uint8_t header[kHeaderBytes];
  if (std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0 ||
      std::fread(header, 1, kHeaderBytes, file_) != static_cast<size_t>(kHeaderBytes))
    return false;
  if (bigEndian(header, 4) != kSyncWord) return false;
  timestamp = static_cast<int64_t>(bigEndian(header + 12, 8));
  channel_length = static_cast<uint32_t>(bigEndian(header + 20, 4));
  data_length = static_cast<uint32_t>(bigEndian(header + 24, 4));
  return true;
}

/// Finds the next sync word after a corrupt event at `offset`; false when there is none.
bool LcmLogReader::resyncAfter(int64_t offset) {
  if (std::fseek(file_, static_cast<long>(offset + 1), SEEK_SET) != 0) return false;
  uint32_t window = 0;
  int64_t position = offset + 1;
  for (int c; (c = std::fgetc(file_)) != EOF; ++position) {
    window = window << 8 | static_cast<uint32_t>(c);
    if (window == kSyncWord && position - 3 > offset) {
      warn("corrupt event at byte " + std::to_string(offset) + " (after " + std::to_string(events_) +
           " events): skipped " + std::to_string(position - 3 - offset) + " bytes to the next event");
      offset_ = position - 3;
      return true;
    }
  }
  warn("corrupt event at byte " + std::to_string(offset) + " (after " + std::to_string(events_) +
       " events) and no event after it: the rest of the file is skipped");
  return false;
}

bool LcmLogReader::next(LogEvent& event) {
  while (file_ && offset_ < size_) {
    int64_t timestamp = 0;
    uint32_t channel_length = 0, data_length = 0;
    const int64_t left = size_ - offset_;
    if (left < kHeaderBytes) {
      warn("truncated at byte " + std::to_string(offset_) + " after " + std::to_string(events_) +
           " events: the last event is incomplete");
      return false;
    }
    if (!readHeaderAt(offset_, timestamp, channel_length, data_length) || channel_length == 0 ||
        channel_length > kMaxChannelLength || data_length > kMaxDataLength) {
      if (!resyncAfter(offset_)) return false;
      continue;
    }
    const int64_t length = kHeaderBytes + static_cast<int64_t>(channel_length) + data_length;
    if (length > left) {
      warn("truncated at byte " + std::to_string(offset_) + " after " + std::to_string(events_) +
           " events: the last event is incomplete");
      return false;
    }
    std::string channel(channel_length, '\0');
    event.data.resize(data_length);
    if (std::fread(channel.data(), 1, channel_length, file_) != channel_length ||
        std::fread(event.data.data(), 1, data_length, file_) != data_length) {
      warn("read error at byte " + std::to_string(offset_));
      return false;
    }
    event.utime = timestamp;
    event.channel = std::move(channel);
    offset_ += length;
    ++events_;
    return true;
  }
  return false;
}

void LcmLogReader::printWarnings() const {
  for (const std::string& warning : warnings_) std::cerr << "warning: " << warning << "\n";
}

double LcmLogReader::progress() const {
  return size_ <= 0 ? 1.0 : static_cast<double>(offset_) / static_cast<double>(size_);
}

LcmLogWriter::LcmLogWriter(const std::string& path) : path_(path), tmp_path_(path + ".tmp") {
  log_ = std::make_unique<lcm::LogFile>(tmp_path_, "w");
  if (!log_->good()) throw std::runtime_error("cannot write LCM log '" + tmp_path_ + "'");
}

LcmLogWriter::~LcmLogWriter() {
  if (!log_) return;
  log_.reset();
  std::error_code ec;
  std::filesystem::remove(tmp_path_, ec);
}

void LcmLogWriter::writeRaw(const std::string& channel, int64_t utime, const void* data, size_t size) {
  lcm::LogEvent e;
  e.eventnum = events_++;
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<int32_t>(size);
  e.data = const_cast<void*>(data);
  if (log_->writeEvent(&e) != 0) {
    log_.reset();
    std::error_code ec;
    std::filesystem::remove(tmp_path_, ec);
    throw std::runtime_error("cannot write '" + path_ + "' (disk full?): nothing written under that name");
  }
}

void LcmLogWriter::close() {
  if (!log_) return;
  std::FILE* file = log_->getFilePtr();
  const bool written = std::fflush(file) == 0 && !std::ferror(file) && fsync(fileno(file)) == 0;
  log_.reset();
  std::error_code ec;
  if (!written) {
    std::filesystem::remove(tmp_path_, ec);
    throw std::runtime_error("cannot finish '" + path_ + "' (disk full?): nothing written under that name");
  }
  std::filesystem::rename(tmp_path_, path_, ec);
  if (ec) throw std::runtime_error("cannot rename '" + tmp_path_ + "' to '" + path_ + "': " + ec.message());
}

}  // namespace polarslam
