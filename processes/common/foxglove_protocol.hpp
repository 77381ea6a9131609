#pragma once
// The Foxglove WebSocket protocol (subprotocol foxglove.websocket.v1, JSON encoding), server
// side, without the network: the channel table, the server's JSON and binary frames, and one
// client's session state (subscriptions, client channels) that turns the client's text and
// binary frames into actions or protocol errors. polarslam-bridge runs it over websocketpp.
// Spec: github.com/foxglove/ws-protocol (docs/spec.md).
#include <nlohmann/json.hpp>

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace polarslam::foxglove {

inline constexpr const char* kSubprotocol = "foxglove.websocket.v1";

struct Channel {
  uint32_t id = 0;
  std::string topic, schema_name;
};

/// The server's channels (one topic each), advertised to every client when it connects.
class ChannelTable {
 public:
  /// Adds a topic with a schema known to foxglove::schema(); returns its channel id.
  uint32_t add(const std::string& topic, const std::string& schema_name);
  std::optional<uint32_t> find(const std::string& topic) const;
  const std::vector<Channel>& channels() const { return channels_; }
  /// {"op":"advertise","channels":[...]} with every channel, encoding json, its JSON schema.
  std::string advertiseMessage() const;

 private:
  std::vector<Channel> channels_;
};

enum class StatusLevel { Info = 0, Warning = 1, Error = 2 };

std::string serverInfoMessage(const std::string& name, const std::vector<std::string>& capabilities,
                              const std::map<std::string, std::string>& metadata = {});
std::string statusMessage(StatusLevel level, const std::string& message);
/// Binary "message data" frame: opcode 1, subscription id (uint32 LE), receive time (uint64 LE, ns), payload.
std::string messageDataFrame(uint32_t subscription_id, uint64_t receive_time_ns, std::string_view payload);

/// A message a client published on one of its advertised channels (capability clientPublish).
struct ClientPublication {
  std::string topic;
  nlohmann::json payload;
};

/// One client's protocol state. Every malformed or unsupported frame yields an error status for
/// the client (and a short reason for the bridge's rejection counters); nothing throws.
class ClientSession {
 public:
  /// `publish_topics`: topics a client may publish on (empty: capability clientPublish is off).
  ClientSession(const ChannelTable& channels, std::vector<std::string> publish_topics);

  struct Outcome {
    std::vector<std::string> replies;  ///< status messages for this client
    std::vector<std::string> errors;   ///< reasons, one per protocol error, for the counters
    std::vector<ClientPublication> publications;
  };
  Outcome onText(std::string_view text);
  Outcome onBinary(std::string_view data);

  /// The client's subscription id for a server channel, if it subscribed to it.
  std::optional<uint32_t> subscriptionFor(uint32_t channel_id) const;

 private:
  void subscribe(const nlohmann::json& message, Outcome& out);
  void unsubscribe(const nlohmann::json& message, Outcome& out);
  void advertise(const nlohmann::json& message, Outcome& out);
  void unadvertise(const nlohmann::json& message, Outcome& out);

  const ChannelTable& channels_;
  std::vector<std::string> publish_topics_;
  std::map<uint32_t, uint32_t> channel_of_subscription_, subscription_of_channel_;
  std::map<uint32_t, std::string> client_topics_;  ///< client channel id → topic
};

/// A FIFO that keeps at most `capacity` items: pushing onto a full queue drops the oldest.
template <typename T>
class DropOldestQueue {
 public:
  explicit DropOldestQueue(size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}
  /// Returns true when an old item had to be dropped to make room.
  bool push(T item) {
    const bool full = items_.size() >= capacity_;
    if (full) {
      items_.pop_front();
      ++dropped_;
    }
    items_.push_back(std::move(item));
    return full;
  }
  bool empty() const { return items_.empty(); }
  size_t size() const { return items_.size(); }
  T pop() {
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }
  uint64_t dropped() const { return dropped_; }

 private:
  size_t capacity_;
  std::deque<T> items_;
  uint64_t dropped_ = 0;
};

}  // namespace polarslam::foxglove
