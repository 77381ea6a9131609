#pragma once
// The network side of polarslam-bridge: one websocketpp (standalone asio) server on its own
// thread that speaks the Foxglove WebSocket protocol and, on the same port, serves the built-in
// page over plain HTTP. The LCM thread hands messages over with broadcast(), which never blocks:
// each client has a bounded queue that drops its oldest message when the client cannot keep up.
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "common/foxglove_protocol.hpp"

namespace polarslam {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  uint16_t port = 8765;
  std::string web_root;                     ///< folder of the page (index.html, …); "" = no page
  std::vector<std::string> publish_topics;  ///< topics clients may publish on ("" list = read-only)
  size_t queue_capacity = 64;               ///< messages waiting per client before the oldest is dropped
  size_t queue_bytes = 16 * 1024 * 1024;    ///< … and bytes
  size_t max_clients = 64;
  std::string name = "polarslam-bridge";
  std::map<std::string, std::string> metadata;  ///< serverInfo metadata (the page reads its topic names there)
};

/// What happened on the network since the last takeEvents(): for the LCM thread to count and act on.
struct ServerEvents {
  std::vector<std::string> errors;  ///< protocol errors and refused connections, by kind
  std::vector<foxglove::ClientPublication> publications;
  uint64_t dropped = 0;             ///< messages dropped from slow clients' queues
  std::vector<std::string> log;     ///< connects and disconnects, for stderr
};

class BridgeServer {
 public:
  BridgeServer(ServerOptions options, const foxglove::ChannelTable& channels);
  ~BridgeServer();
  BridgeServer(const BridgeServer&) = delete;
  BridgeServer& operator=(const BridgeServer&) = delete;

  /// Listens (throws std::runtime_error when the address is taken or invalid) and starts the thread.
  void start();
  void stop();
  /// Whether any client has subscribed to `channel_id` (a message for none need not be made); thread-safe.
  bool subscribed(uint32_t channel_id) const;
  /// Queues `payload` (a JSON message) for every client subscribed to `channel_id`; thread-safe.
  void broadcast(uint32_t channel_id, uint64_t receive_time_ns, std::string payload);
  ServerEvents takeEvents();
  size_t clients() const { return clients_.load(); }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::atomic<size_t> clients_{0};
};

}  // namespace polarslam
