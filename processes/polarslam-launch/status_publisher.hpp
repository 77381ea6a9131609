#pragma once
// PROCESS_STATUS for every supervised command, as the launcher sees it (state, pid, restarts,
// CPU, memory). The processes' own PROCESS_STATUS (message counters) uses their program names.
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>

#include "launch/process_table.hpp"

namespace polarslam {

class StatusPublisher {
 public:
  /// Throws when LCM cannot be opened at `lcm_url`.
  StatusPublisher(const std::string& lcm_url, std::string host);
  void publish(const ProcessRecord& record);

 private:
  std::unique_ptr<lcm::LCM> lcm_;
  std::string host_;
};

}  // namespace polarslam
