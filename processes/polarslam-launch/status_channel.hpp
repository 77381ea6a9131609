#pragma once
// The launcher on PROCESS_STATUS: it publishes every supervised command as it sees it (state, pid,
// restarts, CPU, memory) and hears the processes' own reports (message counters, published under
// their program names), whose "running" says a process has subscribed and is ready for input.
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>
#include <vector>

#include "launch/process_table.hpp"
#include "polarslam/process_status_t.hpp"

namespace polarslam {

class StatusChannel {
 public:
  /// Throws when LCM cannot be opened at `lcm_url`. `host` labels the launcher's messages.
  StatusChannel(const std::string& lcm_url, std::string host);
  void publish(const ProcessRecord& record);

  /// Readable when reports are waiting (for poll).
  int fd() { return lcm_->getFileno(); }
  /// The reports from this machine that have arrived (the launcher's own included), without waiting.
  std::vector<process_status_t> receive();

 private:
  void onReport(const lcm::ReceiveBuffer*, const std::string&, const process_status_t* msg);

  std::unique_ptr<lcm::LCM> lcm_;
  std::string host_, local_host_;
  std::vector<process_status_t> received_;
};

}  // namespace polarslam
