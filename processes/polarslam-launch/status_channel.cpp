#include "status_channel.hpp"

#include <stdexcept>
#include <utility>

#include "common/process_context.hpp"

namespace polarslam {

StatusChannel::StatusChannel(const std::string& lcm_url, std::string host)
    : lcm_(std::make_unique<lcm::LCM>(lcm_url)), host_(std::move(host)), local_host_(hostName()) {
  if (!lcm_->good())
    throw std::runtime_error("cannot open LCM at '" + lcm_url +
                             "' (no multicast route? try: ip route add 224.0.0.0/4 dev lo)");
  lcm_->subscribe("PROCESS_STATUS", &StatusChannel::onReport, this);
}

std::vector<process_status_t> StatusChannel::receive() {
  while (lcm_->handleTimeout(0) > 0) {
  }
  return std::exchange(received_, {});
}

void StatusChannel::onReport(const lcm::ReceiveBuffer*, const std::string&, const process_status_t* msg) {
  if (msg->host == local_host_) received_.push_back(*msg);
}

void StatusChannel::publish(const ProcessRecord& record) {
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
