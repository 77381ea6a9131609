#include "common/foxglove_protocol.hpp"

#include <algorithm>

#include "common/foxglove_schemas.hpp"

namespace polarslam::foxglove {
namespace {

using Json = nlohmann::json;

constexpr uint8_t kMessageDataOpcode = 1;
constexpr size_t kMaxIdsPerRequest = 10000;

void putLittleEndian(std::string& out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((value >> (8 * i)) & 0xff);
}

/// A uint32 field of `object`, or nothing when absent, not an integer or out of range.
std::optional<uint32_t> idField(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key)) return std::nullopt;
  const Json& v = object[key];
  if (!v.is_number_integer()) return std::nullopt;
  const int64_t id = v.get<int64_t>();
  if (id < 0 || id > int64_t{UINT32_MAX}) return std::nullopt;
  return static_cast<uint32_t>(id);
}

bool stringField(const Json& object, const char* key) { return object.contains(key) && object[key].is_string(); }

/// The array `key` of `message`, or nullptr (with an error recorded) when absent or too long.
const Json* arrayField(const Json& message, const char* key, const std::string& op, ClientSession::Outcome& out) {
  if (!message.contains(key) || !message[key].is_array() || message[key].size() > kMaxIdsPerRequest) {
    const std::string why = op + ": '" + key + "' must be an array of at most " + std::to_string(kMaxIdsPerRequest);
    out.replies.push_back(statusMessage(StatusLevel::Error, why));
    out.errors.push_back("client: malformed " + op);
    return nullptr;
  }
  return &message[key];
}

void fail(ClientSession::Outcome& out, const std::string& message, const std::string& kind) {
  out.replies.push_back(statusMessage(StatusLevel::Error, message));
  out.errors.push_back(kind);
}

}  // namespace

uint32_t ChannelTable::add(const std::string& topic, const std::string& schema_name) {
  schema(schema_name);  // throws for a schema we cannot describe
  const auto id = static_cast<uint32_t>(channels_.size() + 1);
  channels_.push_back({id, topic, schema_name});
  return id;
}

std::optional<uint32_t> ChannelTable::find(const std::string& topic) const {
  for (const Channel& c : channels_)
    if (c.topic == topic) return c.id;
  return std::nullopt;
}

std::string ChannelTable::advertiseMessage() const {
  Json list = Json::array();
  for (const Channel& c : channels_)
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", "json"},
                    {"schemaName", c.schema_name},
                    {"schema", schema(c.schema_name).dump()},
                    {"schemaEncoding", "jsonschema"}});
  return Json{{"op", "advertise"}, {"channels", list}}.dump();
}

std::string serverInfoMessage(const std::string& name, const std::vector<std::string>& capabilities,
                              const std::map<std::string, std::string>& metadata) {
  return Json{{"op", "serverInfo"}, {"name", name}, {"capabilities", capabilities}, {"supportedEncodings", {"json"}},
              {"metadata", metadata}}
      .dump();
}

std::string statusMessage(StatusLevel level, const std::string& message) {
  return Json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump();
}

std::string messageDataFrame(uint32_t subscription_id, uint64_t receive_time_ns, std::string_view payload) {
  std::string frame;
  frame.reserve(1 + 4 + 8 + payload.size());
  frame += static_cast<char>(kMessageDataOpcode);
  putLittleEndian(frame, subscription_id, 4);
  putLittleEndian(frame, receive_time_ns, 8);
  frame.append(payload);
  return frame;
}

ClientSession::ClientSession(const ChannelTable& channels, std::vector<std::string> publish_topics)
    : channels_(channels), publish_topics_(std::move(publish_topics)) {}

std::optional<uint32_t> ClientSession::subscriptionFor(uint32_t channel_id) const {
  const auto it = subscription_of_channel_.find(channel_id);
  if (it == subscription_of_channel_.end()) return std::nullopt;
  return it->second;
}

ClientSession::Outcome ClientSession::onText(std::string_view text) {
  Outcome out;
  const Json message = Json::parse(text, nullptr, false);
  if (message.is_discarded() || !message.is_object()) {
    fail(out, "message is not a JSON object", "client: malformed JSON");
    return out;
  }
  if (!stringField(message, "op")) {
    fail(out, "message has no string 'op'", "client: message without op");
    return out;
  }
  const std::string op = message["op"];
  if (op == "subscribe") subscribe(message, out);
  else if (op == "unsubscribe") unsubscribe(message, out);
  else if (op == "advertise") advertise(message, out);
  else if (op == "unadvertise") unadvertise(message, out);
  else fail(out, "unsupported operation '" + op.substr(0, 64) + "'", "client: unsupported op");
  return out;
}

void ClientSession::subscribe(const Json& message, Outcome& out) {
  const Json* list = arrayField(message, "subscriptions", "subscribe", out);
  if (!list) return;
  for (const Json& s : *list) {
    const auto id = idField(s, "id"), channel = idField(s, "channelId");
    if (!id || !channel) {
      fail(out, "subscribe: each subscription needs integer 'id' and 'channelId'", "client: malformed subscribe");
    } else if (*channel == 0 || *channel > channels_.channels().size()) {
      fail(out, "subscribe: unknown channel " + std::to_string(*channel), "client: subscribe to unknown channel");
    } else if (channel_of_subscription_.count(*id)) {
      fail(out, "subscribe: subscription id " + std::to_string(*id) + " is already in use", "client: duplicate subscription id");
    } else if (subscription_of_channel_.count(*channel)) {
      fail(out, "subscribe: already subscribed to channel " + std::to_string(*channel), "client: duplicate subscription");
    } else {
      channel_of_subscription_[*id] = *channel;
      subscription_of_channel_[*channel] = *id;
    }
  }
}

void ClientSession::unsubscribe(const Json& message, Outcome& out) {
  const Json* list = arrayField(message, "subscriptionIds", "unsubscribe", out);
  if (!list) return;
  for (const Json& v : *list) {
    const auto it = v.is_number_unsigned() ? channel_of_subscription_.find(v.get<uint32_t>()) : channel_of_subscription_.end();
    if (it == channel_of_subscription_.end()) {
      fail(out, "unsubscribe: unknown subscription " + v.dump().substr(0, 32), "client: unsubscribe unknown subscription");
      continue;
    }
    subscription_of_channel_.erase(it->second);
    channel_of_subscription_.erase(it);
  }
}

void ClientSession::advertise(const Json& message, Outcome& out) {
  if (publish_topics_.empty()) {
    fail(out, "advertise: this server does not accept client publishing (read-only)", "client: advertise while read-only");
    return;
  }
  const Json* list = arrayField(message, "channels", "advertise", out);
  if (!list) return;
  for (const Json& c : *list) {
    const auto id = idField(c, "id");
    if (!id || !stringField(c, "topic") || !stringField(c, "encoding") || !stringField(c, "schemaName")) {
      fail(out, "advertise: each channel needs 'id', 'topic', 'encoding' and 'schemaName'", "client: malformed advertise");
      continue;
    }
    const std::string topic = c["topic"];
    if (std::find(publish_topics_.begin(), publish_topics_.end(), topic) == publish_topics_.end()) {
      fail(out, "advertise: clients may not publish on '" + topic.substr(0, 64) + "'", "client: advertise on a refused topic");
    } else if (c["encoding"] != "json") {
      fail(out, "advertise: only the json encoding is accepted", "client: advertise with unsupported encoding");
    } else if (client_topics_.count(*id)) {
      fail(out, "advertise: client channel " + std::to_string(*id) + " already advertised", "client: duplicate advertise");
    } else {
      client_topics_[*id] = topic;
    }
  }
}

void ClientSession::unadvertise(const Json& message, Outcome& out) {
  const Json* list = arrayField(message, "channelIds", "unadvertise", out);
  if (!list) return;
  for (const Json& v : *list)
    if (!v.is_number_unsigned() || client_topics_.erase(v.get<uint32_t>()) == 0)
      fail(out, "unadvertise: unknown client channel " + v.dump().substr(0, 32), "client: unadvertise unknown channel");
}

ClientSession::Outcome ClientSession::onBinary(std::string_view data) {
  Outcome out;
  if (data.size() < 5 || static_cast<uint8_t>(data[0]) != kMessageDataOpcode) {
    fail(out, "binary message: only client message data (opcode 1, channel id, payload) is supported",
         "client: unsupported binary message");
    return out;
  }
  uint32_t channel = 0;
  for (int i = 0; i < 4; ++i) channel |= uint32_t{static_cast<uint8_t>(data[1 + i])} << (8 * i);
  const auto topic = client_topics_.find(channel);
  if (topic == client_topics_.end()) {
    fail(out, "message data on client channel " + std::to_string(channel) + ", which was not advertised",
         "client: message on unadvertised channel");
    return out;
  }
  Json payload = Json::parse(data.substr(5), nullptr, false);
  if (payload.is_discarded() || !payload.is_object()) {
    fail(out, "message data on '" + topic->second + "' is not a JSON object", "client: malformed message data");
    return out;
  }
  out.publications.push_back({topic->second, std::move(payload)});
  return out;
}

}  // namespace polarslam::foxglove
