#include "status_publisher.hpp"

#include <stdexcept>

#include "common/process_context.hpp"
#include "polarslam/process_status_t.hpp"

namespace polarslam {

StatusPublisher::StatusPublisher(const std::string& lcm_url, std::string host)
    : lcm_(std::make_unique<lcm::LCM>(lcm_url)), host_(std::move(host)) {
  if (!lcm_->good())
    throw std::runtime_error("cannot open LCM at '" + lcm_url +
                             "' (no multicast route? try: ip route add 224.0.0.0/4 dev lo)");
}

void StatusPublisher::publish(const ProcessRecord& record) {
  process_status_t msg{};
  msg.utime = nowUtime();
  msg.name = record.spec.name;
  msg.host = host_;
  msg.pid = record.pid > 0 ? record.pid : 0;
  msg.state = stateName(record.state);
  msg.restarts = record.restarts;
  msg.num_reject_kinds = 0;
  msg.cpu_percent = record.cpu_percent;
  msg.rss_mb = record.rss_mb;
  lcm_->publish("PROCESS_STATUS", &msg);
}

}  // namespace polarslam
