#include "common/lcm_log.hpp"

#include <cstdio>
#include <filesystem>

namespace polarslam {

LcmLogReader::LcmLogReader(const std::string& path) {
  std::error_code ec;
  size_ = static_cast<long>(std::filesystem::file_size(path, ec));
  if (ec) throw std::runtime_error("cannot open LCM log '" + path + "': " + ec.message());
  log_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!log_->good()) throw std::runtime_error("cannot open LCM log '" + path + "'");
}

bool LcmLogReader::next(LogEvent& event) {
  const lcm::LogEvent* e = log_->readNextEvent();
  if (!e) return false;
  event.utime = e->timestamp;
  event.channel = e->channel;
  const auto* bytes = static_cast<const uint8_t*>(e->data);
  event.data.assign(bytes, bytes + e->datalen);
  return true;
}

double LcmLogReader::progress() const {
  if (size_ <= 0) return 1.0;
  FILE* f = log_->getFilePtr();
  return f ? static_cast<double>(std::ftell(f)) / static_cast<double>(size_) : 1.0;
}

LcmLogWriter::LcmLogWriter(const std::string& path) : path_(path), tmp_path_(path + ".tmp") {
  log_ = std::make_unique<lcm::LogFile>(tmp_path_, "w");
  if (!log_->good()) throw std::runtime_error("cannot write LCM log '" + tmp_path_ + "'");
}

LcmLogWriter::~LcmLogWriter() {
  try {
    close();
  } catch (...) {
  }
}

void LcmLogWriter::writeRaw(const std::string& channel, int64_t utime, const void* data, size_t size) {
  lcm::LogEvent e;
  e.eventnum = events_++;
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<int32_t>(size);
  e.data = const_cast<void*>(data);
  if (log_->writeEvent(&e) != 0) throw std::runtime_error("write failed on '" + tmp_path_ + "'");
}

void LcmLogWriter::close() {
  if (!log_) return;
  log_.reset();  // flushes and closes
  std::filesystem::rename(tmp_path_, path_);
}

}  // namespace polarslam
