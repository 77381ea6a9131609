// polarslam spy: a command-line lcm-spy (for ssh and CI): counts, rates and types per channel.
// polarslam log-info: the same table for an LCM log file.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>

#include "command_registry.hpp"
#include "common/lcm_log.hpp"
#include "common/lcm_types.hpp"
#include "common/process_context.hpp"

namespace polarslam {
namespace {

struct ChannelStats {
  int64_t count = 0, bytes = 0, first_utime = 0, last_utime = 0;
  std::string type;
};

class ChannelTable {
 public:
  void add(const std::string& channel, int64_t utime, const uint8_t* data, size_t size) {
    ChannelStats& s = stats_[channel];
    if (s.count++ == 0) {
      s.first_utime = utime;
      s.type = lcmTypeName(data, size);
      if (s.type.empty()) s.type = "(unknown type)";
    }
    s.last_utime = utime;
    s.bytes += static_cast<int64_t>(size);
  }
  void print(std::ostream& out) const {
    out << "channel              type                              count      rate_hz   avg_bytes\n";
    for (const auto& [channel, s] : stats_) {
      const double span = static_cast<double>(s.last_utime - s.first_utime) * 1e-6;
      const double rate = span > 0.0 ? static_cast<double>(s.count - 1) / span : 0.0;
      char line[256];
      std::snprintf(line, sizeof(line), "%-20s %-32s %8lld %12.2f %11lld\n", channel.c_str(), s.type.c_str(),
                    static_cast<long long>(s.count), rate, static_cast<long long>(s.bytes / s.count));
      out << line;
    }
  }
  bool empty() const { return stats_.empty(); }

 private:
  std::map<std::string, ChannelStats> stats_;
};

struct SpyHandler {
  ChannelTable* table;
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    table->add(channel, nowUtime(), static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
  }
};

void setupSpy(CLI::App& sub) {
  auto seconds = std::make_shared<double>(5.0);
  auto url = std::make_shared<std::string>();
  sub.add_option("--seconds", *seconds, "how long to listen")->capture_default_str();
  sub.add_option("--lcm-url", *url, "LCM URL (default: $LCM_DEFAULT_URL or multicast TTL 0)");
  sub.callback([seconds, url] {
    lcm::LCM lcm(resolveLcmUrl(*url));
    if (!lcm.good()) throw std::runtime_error("cannot open LCM (no multicast route?)");
    ChannelTable table;
    SpyHandler handler{&table};
    lcm.subscribe(".*", &SpyHandler::onMessage, &handler);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(*seconds);
    while (std::chrono::steady_clock::now() < end) lcm.handleTimeout(50);
    table.print(std::cout);
    if (table.empty()) std::cout << "(no messages in " << *seconds << " s)\n";
  });
}

void setupLogInfo(CLI::App& sub) {
  auto path = std::make_shared<std::string>();
  sub.add_option("--log", *path, "LCM log file")->required()->check(CLI::ExistingFile);
  sub.callback([path] {
    LcmLogReader reader(*path);
    ChannelTable table;
    LogEvent event;
    while (reader.next(event)) table.add(event.channel, event.utime, event.data.data(), event.data.size());
    table.print(std::cout);
    reader.printWarnings();
  });
}

RegisterCommand reg_spy("spy", "Listen to LCM traffic and print channels, types, counts and rates", setupSpy);
RegisterCommand reg_info("log-info", "Print channels, types, counts and rates of an LCM log", setupLogInfo);

}  // namespace
}  // namespace polarslam
