#include "common/input_journal.hpp"

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace polarslam {

InputJournal::InputJournal(std::string path, std::chrono::milliseconds flush_period, std::string launch_id)
    : path_(std::move(path)), launch_id_(std::move(launch_id)), flush_period_(flush_period) {}

std::string InputJournal::currentLaunchId() {
  const char* id = std::getenv("POLARSLAM_LAUNCH_ID");
  return id ? id : "";
}

std::vector<LogEvent> InputJournal::readEvents() {
  std::vector<LogEvent> events;
  std::error_code size_error;
  if (std::filesystem::file_size(path_, size_error) == 0 || size_error) return events;
  LcmLogReader reader(path_);
  LogEvent event;
  std::string owner;  // a journal without a header was written by hand-started processes
  generation_ = 0;
  if (reader.next(event)) {
    if (event.channel == kHeaderChannel) {
      owner.assign(event.data.begin(), event.data.end());
      // "LAUNCH_ID" or, once cut, "LAUNCH_ID\ngeneration N".
      if (const size_t newline = owner.find("\ngeneration "); newline != std::string::npos) {
        generation_ = std::strtoull(owner.c_str() + newline + 12, nullptr, 10);
        owner.resize(newline);
      }
    } else {
      events.push_back(event);
    }
  }
  if (owner != launch_id_) {
    refused_ = "journal '" + path_ + "' belongs to launch '" + (owner.empty() ? "(started by hand)" : owner) +
               "', not to this one ('" + (launch_id_.empty() ? "(started by hand)" : launch_id_) +
               "'): stale (a reused run folder?), not replayed; kept as '" + path_ + ".stale'";
    std::filesystem::rename(path_, path_ + ".stale");
    return {};
  }
  while (reader.next(event)) events.push_back(event);
  return events;
}

std::vector<LogEvent> InputJournal::recover() {
  std::vector<LogEvent> events = readEvents();
  rewrite(generation_, events);
  return events;
}

void InputJournal::rewrite(uint64_t generation, const std::vector<LogEvent>& events) {
  const std::string tmp = path_ + ".tmp";
  log_ = std::make_unique<lcm::LogFile>(tmp, "w");
  if (!log_->good()) throw std::runtime_error("cannot write journal '" + tmp + "'");
  generation_ = generation;
  const std::string header = generation == 0 ? launch_id_ : launch_id_ + "\ngeneration " + std::to_string(generation);
  append(kHeaderChannel, 0, header.data(), header.size());
  events_ = 0;
  for (const LogEvent& e : events) append(e.channel, e.utime, e.data.data(), e.data.size());
  std::fflush(log_->getFilePtr());
  std::error_code ec;
  std::filesystem::rename(tmp, path_, ec);  // the open file goes on under its final name
  if (ec) throw std::runtime_error("cannot rename journal '" + tmp + "': " + ec.message());
  last_flush_ = std::chrono::steady_clock::now();
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
  if (channel != kHeaderChannel) ++events_;
}

void InputJournal::flushIfDue() {
  const auto now = std::chrono::steady_clock::now();
  if (!log_ || (flush_period_.count() > 0 && now - last_flush_ < flush_period_)) return;
  std::fflush(log_->getFilePtr());
  last_flush_ = now;
}

void addJournalOptions(CLI::App& app, JournalOptions& options) {
  app.add_option("--journal", options.path,
                 "crash recovery: append every input message to this file (an LCM log) and, on start, "
                 "resume by replaying it");
  app.add_option("--journal-flush", options.flush_period,
                 "s between flushes of the journal to the kernel (0: after every message, which a kill -9 "
                 "cannot lose)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

}  // namespace polarslam
