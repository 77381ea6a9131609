#include "common/input_journal.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace polarslam {

InputJournal::InputJournal(std::string path, std::chrono::milliseconds flush_period)
    : path_(std::move(path)), flush_period_(flush_period) {}

std::vector<LogEvent> InputJournal::recover() {
  std::vector<LogEvent> events;
  std::error_code size_error;
  if (std::filesystem::file_size(path_, size_error) > 0 && !size_error) {
    LcmLogReader reader(path_);
    LogEvent event;
    while (reader.next(event)) events.push_back(event);
  }
  const std::string tmp = path_ + ".tmp";
  log_ = std::make_unique<lcm::LogFile>(tmp, "w");
  if (!log_->good()) throw std::runtime_error("cannot write journal '" + tmp + "'");
  for (const LogEvent& e : events) append(e.channel, e.utime, e.data.data(), e.data.size());
  std::fflush(log_->getFilePtr());
  std::error_code ec;
  std::filesystem::rename(tmp, path_, ec);  // the open file goes on under its final name
  if (ec) throw std::runtime_error("cannot rename journal '" + tmp + "': " + ec.message());
  last_flush_ = std::chrono::steady_clock::now();
  return events;
}

void InputJournal::append(const std::string& channel, int64_t utime, const void* data, size_t size) {
  if (!log_) throw std::logic_error("InputJournal::append before recover()");
  lcm::LogEvent event;
  event.eventnum = 0;
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(size);
  event.data = const_cast<void*>(data);
  if (log_->writeEvent(&event) != 0) throw std::runtime_error("cannot append to journal '" + path_ + "'");
}

void InputJournal::flushIfDue() {
  const auto now = std::chrono::steady_clock::now();
  if (!log_ || now - last_flush_ < flush_period_) return;
  std::fflush(log_->getFilePtr());
  last_flush_ = now;
}

void addJournalOptions(CLI::App& app, JournalOptions& options) {
  app.add_option("--journal", options.path,
                 "crash recovery: append every input message to this file (an LCM log) and, on start, "
                 "resume by replaying it");
  app.add_option("--journal-flush", options.flush_period, "s between flushes of the journal to disk")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

}  // namespace polarslam
