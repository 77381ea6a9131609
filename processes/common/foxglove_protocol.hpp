#pragma once
// The Foxglove WebSocket protocol (subprotocol foxglove.websocket.v1, JSON encoding), server
// side, without the network: the channel table, the server's JSON and binary frames, and one
// client's session state (subscriptions, client channels) that turns the client's text and
// binary frames into actions or protocol errors. polarslam-bridge runs it over websocketpp.
// Spec: github.com/foxglove/ws-protocol (docs/spec.md).
#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstddef>
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

/// The frames waiting for one client: at most `capacity` frames and `max_bytes` bytes; pushing
/// beyond either drops the oldest (but never the frame just pushed).
class FrameQueue {
 public:
  explicit FrameQueue(size_t capacity, size_t max_bytes = SIZE_MAX)
      : capacity_(capacity == 0 ? 1 : capacity), max_bytes_(max_bytes) {}
  /// Returns how many old frames were dropped to make room.
  size_t push(std::string frame) {
    bytes_ += frame.size();
    frames_.push_back(std::move(frame));
    size_t dropped = 0;
    while (frames_.size() > 1 && (frames_.size() > capacity_ || bytes_ > max_bytes_)) {
      bytes_ -= frames_.front().size();
      frames_.pop_front();
      ++dropped;
    }
    dropped_ += dropped;
    return dropped;
  }
  bool empty() const { return frames_.empty(); }
  size_t size() const { return frames_.size(); }
  size_t bytes() const { return bytes_; }
  std::string pop() {
    std::string frame = std::move(frames_.front());
    frames_.pop_front();
    bytes_ -= frame.size();
    return frame;
  }
  uint64_t dropped() const { return dropped_; }

 private:
  size_t capacity_, max_bytes_, bytes_ = 0;
  std::deque<std::string> frames_;
  uint64_t dropped_ = 0;
};

}  // namespace polarslam::foxglove
